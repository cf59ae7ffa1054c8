// Calls the installed particle engine: the Hagen-Poiseuille pressure drop of the README's viscosity
// example (100 Pa.s through the 11G cannula, 2.388 mm bore, 90 mm long, at 0.05 ml/s), checked against
// the law written out here, dP = 128 mu L Q / (pi D^4) = 0.5637 MPa. Exit 0 when they agree to 1e-12.
#include "cementsph/sph/HagenPoiseuille.h"

#include <cmath>
#include <cstdio>

int main() {
  const double mu = 100.0, length = 0.090, flow = 0.05e-6, diameter = 2.388e-3;
  const double expected = 128.0 * mu * length * flow / (M_PI * std::pow(diameter, 4));
  const double got = cementsph::sph::hagenPoiseuillePressureDrop(mu, length, flow, diameter);
  std::printf("pressure drop %.6f MPa (expected %.6f MPa)\n", got / 1e6, expected / 1e6);
  return std::abs(got - expected) <= 1e-12 * expected ? 0 : 1;
}
