// Kernel oracles (model-notes 4): unit integral, zero gradient sum on a lattice, spiky gradient at 0.
#include "cementsph/sph/Kernels.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace cementsph::sph;

namespace {
// Radial integral 4 pi int_0^{2h} W(r) r^2 dr by Simpson's rule (exact to ~1e-12 for these piecewise
// polynomials when the break point q = 1 is a node).
template <class K> double radialIntegral(const K& k) {
  const int n = 2000; // even, and q = 1 falls on node n/2
  const double a = 0.0, b = k.support(), dr = (b - a) / n;
  double s = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double r = a + i * dr;
    const double f = k.value(r) * r * r;
    s += (i == 0 || i == n) ? f : (i % 2 ? 4 * f : 2 * f);
  }
  return 4.0 * kPi * s * dr / 3.0;
}
} // namespace

TEST(SPHKernels, CubicSplineHasUnitIntegral) {
  for (double h : {1e-4, 5e-4, 1.3e-3}) {
    EXPECT_NEAR(radialIntegral(CubicSplineKernel(h)), 1.0, 1e-9) << "h = " << h;
  }
}

TEST(SPHKernels, SpikyHasUnitIntegral) {
  for (double h : {1e-4, 5e-4, 1.3e-3}) {
    EXPECT_NEAR(radialIntegral(SpikyKernel(h)), 1.0, 1e-9) << "h = " << h;
  }
}

TEST(SPHKernels, DerivativeMatchesFiniteDifference) {
  const double h = 1e-3;
  CubicSplineKernel c(h);
  SpikyKernel s(h);
  for (double q : {0.1, 0.5, 0.9, 1.1, 1.5, 1.9}) {
    const double r = q * h, e = 1e-9;
    EXPECT_NEAR(c.derivative(r), (c.value(r + e) - c.value(r - e)) / (2 * e),
                1e-6 * std::abs(c.derivative(r)) + 1e-3);
    EXPECT_NEAR(s.derivative(r), (s.value(r + e) - s.value(r - e)) / (2 * e),
                1e-6 * std::abs(s.derivative(r)) + 1e-3);
    EXPECT_NEAR(c.derivativeOverR(r), c.derivative(r) / r, 1e-9 * std::abs(c.derivative(r) / r));
  }
}

TEST(SPHKernels, GradientsSumToZeroOnALattice) {
  // On a full cubic lattice the kernel gradient sum about any site cancels by symmetry; this
  // checks the evaluation is symmetric (round-off only).
  const double d = 1e-3;
  for (double hOverD : {1.0, 1.2, 1.5}) {
    CubicSplineKernel c(hOverD * d);
    SpikyKernel s(hOverD * d);
    double gc[3] = {0, 0, 0}, gs[3] = {0, 0, 0}, scale = 0;
    for (int i = -4; i <= 4; ++i)
      for (int j = -4; j <= 4; ++j)
        for (int k = -4; k <= 4; ++k) {
          if (!i && !j && !k) continue;
          const double x[3] = {i * d, j * d, k * d};
          const double r = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
          for (int a = 0; a < 3; ++a) {
            gc[a] += c.derivative(r) * x[a] / r;
            gs[a] += s.derivative(r) * x[a] / r;
          }
          scale += std::abs(s.derivative(r));
        }
    ASSERT_GT(scale, 0.0); // lattice neighbours are inside the support
    for (int a = 0; a < 3; ++a) {
      EXPECT_LE(std::abs(gc[a]), 1e-12 * scale) << "h/d " << hOverD;
      EXPECT_LE(std::abs(gs[a]), 1e-12 * scale) << "h/d " << hOverD;
    }
  }
}

TEST(SPHKernels, SpikyGradientIsNonZeroAtOrigin) {
  const double h = 1e-3;
  SpikyKernel s(h);
  CubicSplineKernel c(h);
  // Eq. 11: dW/dr(0) = -3 * 15 / (pi (4h)^3) * 4 / h.
  const double expected = -3.0 * 15.0 / (kPi * 64.0 * h * h * h) * 4.0 / h;
  EXPECT_NEAR(s.derivative(0.0), expected, 1e-12 * std::abs(expected));
  EXPECT_NE(s.derivative(0.0), 0.0);
  EXPECT_EQ(c.derivative(0.0), 0.0); // the reason Eq. 11 exists
}

TEST(SPHKernels, ZeroOutsideSupport) {
  const double h = 1e-3;
  EXPECT_EQ(CubicSplineKernel(h).value(2.0 * h), 0.0);
  EXPECT_EQ(SpikyKernel(h).value(2.0 * h), 0.0);
  EXPECT_EQ(CubicSplineKernel(h).derivative(2.5 * h), 0.0);
  EXPECT_EQ(SpikyKernel(h).derivative(2.5 * h), 0.0);
}
