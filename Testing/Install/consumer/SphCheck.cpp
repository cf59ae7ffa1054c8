// The particle engine: the normalisation of its two smoothing kernels, integral of W over space = 1 (the
// cubic spline's sigma = 1/(pi h^3), the spiky's 15/(64 pi h^3) are chosen for that), by Simpson's rule over
// the support written out here; and the Hagen-Poiseuille pressure drop of the README's viscosity example
// (100 Pa.s through the 11G cannula, 2.388 mm bore, 90 mm long, at 0.05 ml/s) against
// dP = 128 mu L Q / (pi D^4) = 0.5637 MPa.
#include "Checks.h"

#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/Kernels.h"

#include <cmath>

namespace {

// Integral of 4 pi r^2 W(r) over [0, 2h], composite Simpson with the kernels' break at r = h on a node.
// W is a piecewise polynomial of degree 3, so the only error is Simpson's on degree-5 pieces: ~1e-14 here.
template <class Kernel>
double volumeIntegral(const Kernel& kernel) {
  const int intervals = 2000;
  const double step = kernel.support() / intervals;
  double sum = 0.0;
  for (int i = 0; i <= intervals; ++i) {
    const double r = i * step;
    const double weight = (i == 0 || i == intervals) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += weight * 4.0 * M_PI * r * r * kernel.value(r);
  }
  return sum * step / 3.0;
}

} // namespace

int checkSph() {
  const double h = 1.14e-3; // m, the kernel radius of the paper's particle spacing (support 2.28 mm)
  int failures = compare("cubic spline kernel, integral of W dV", volumeIntegral(cementsph::sph::CubicSplineKernel(h)), 1.0, 1e-9);
  failures += compare("spiky kernel, integral of W dV", volumeIntegral(cementsph::sph::SpikyKernel(h)), 1.0, 1e-9);
  const double mu = 100.0, length = 0.090, flow = 0.05e-6, diameter = 2.388e-3;
  const double expected = 128.0 * mu * length * flow / (M_PI * std::pow(diameter, 4));
  failures += compare("Hagen-Poiseuille pressure drop, Pa",
                      cementsph::sph::hagenPoiseuillePressureDrop(mu, length, flow, diameter), expected, 1e-12 * expected);
  return failures;
}
