// Small scenes shared by the SPH tests: lattices, channels, random porous boxes.
#pragma once

#include "cementsph/sph/Simulation.h"

#include <cmath>
#include <memory>

namespace cementsph::sph::testing {

// A fully periodic cubic box of n^3 fluid particles at spacing d, mass rho0 d^3.
inline std::unique_ptr<Simulation> periodicLattice(const ModelParameters& m, int n, double d) {
  Domain domain;
  domain.upper.setConstant(n * d);
  domain.periodic = {true, true, true};
  auto sim = std::make_unique<Simulation>(m, domain);
  const double mass = m.restDensity * d * d * d;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        sim->addFluidParticle(Eigen::Vector3d((i + 0.5) * d, (j + 0.5) * d, (k + 0.5) * d), Eigen::Vector3d::Zero(), mass);
  return sim;
}

inline ModelParameters baseModel(double d, double hOverD = 1.0) {
  ModelParameters m;
  m.smoothingLength = hOverD * d;
  m.viscosity = 10.0;
  m.dragCoefficient = 1.0;
  return m;
}

} // namespace cementsph::sph::testing
