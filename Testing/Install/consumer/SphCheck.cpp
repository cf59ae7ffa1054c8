// The particle engine's smoothing kernels (Basafa et al. 2013, Eqs. 10-11), by Simpson's rule over their
// support written out here: each integrates to 1 over space (the cubic spline's sigma = 1/(pi h^3) and the
// spiky's 15/(64 pi h^3) are chosen for that), and the cubic spline's derivative integrates over [0, 2h] to
// W(2h) - W(0) = -sigma = -1/(pi h^3).
#include "Checks.h"

#include "cementsph/sph/Kernels.h"

#include <cmath>

namespace {

// Composite Simpson over [0, 2h] with the kernels' break at r = h on a node. The integrands are piecewise
// polynomials of degree at most 5, so the only error is Simpson's on them: ~1e-14 relative here.
template <class Integrand>
double overSupport(double support, const Integrand& f) {
  const int intervals = 2000;
  const double step = support / intervals;
  double sum = 0.0;
  for (int i = 0; i <= intervals; ++i) {
    const double weight = (i == 0 || i == intervals) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += weight * f(i * step);
  }
  return sum * step / 3.0;
}

template <class Kernel>
double volumeIntegral(const Kernel& kernel) {
  return overSupport(kernel.support(), [&](double r) { return 4.0 * M_PI * r * r * kernel.value(r); });
}

} // namespace

int checkSph() {
  const double h = 1.14e-3; // m, the kernel radius of the paper's particle spacing (support 2.28 mm)
  const cementsph::sph::CubicSplineKernel cubic(h);
  int failures = compare("cubic spline kernel, integral of W dV", volumeIntegral(cubic), 1.0, 1e-9);
  failures += compare("spiky kernel, integral of W dV", volumeIntegral(cementsph::sph::SpikyKernel(h)), 1.0, 1e-9);
  const double sigma = 1.0 / (M_PI * h * h * h);
  failures += compare("cubic spline kernel, integral of dW/dr over [0, 2h] (1/m^3)",
                      overSupport(cubic.support(), [&](double r) { return cubic.derivative(r); }), -sigma, 1e-9 * sigma);
  return failures;
}
