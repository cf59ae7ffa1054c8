// Time integrators (model-notes 3). Each stands in its own source file under src/Integrators/.
#pragma once

#include "cementsph/sph/ModelInterfaces.h"

namespace cementsph::sph {

// The paper's Eq. 8 (central difference) with the drag taken implicitly, which keeps it diagonal:
//   r+ = [2 r - (1 - gamma dt/2) r- + dt^2 a_other] / (1 + gamma dt/2).
// Stable for any gamma; the explicit pressure term still needs the acoustic limit. One constant step.
class CentralDifference : public TimeIntegrator {
public:
  std::string name() const override { return "central-difference"; }
  StepLimits limits(const Simulation& sim) const override;
  void integrate(Simulation& sim, double dt) override;
  bool constantStep() const override { return true; }
};

// Symplectic Euler, v += dt (a - gamma v), r += dt v: for Morris viscosity (viscous and acoustic limits).
class ExplicitEuler : public TimeIntegrator {
public:
  std::string name() const override { return "explicit"; }
  StepLimits limits(const Simulation& sim) const override;
  void integrate(Simulation& sim, double dt) override;
};

// Creeping flow (gamma dt >> 1): inertia negligible, v = a_other / gamma, r += dt v. The step is bounded by
// accuracy (a particle moves at most maxDisplacement h) and, for an equation of state, by the stability
// limit C gamma_min h^2 / cs^2 of the density's diffusion.
class Overdamped : public TimeIntegrator {
public:
  std::string name() const override { return "overdamped"; }
  StepLimits limits(const Simulation& sim) const override;
  void integrate(Simulation& sim, double dt) override;
};

// The limits shared by the schemes that keep inertia: acoustic (C h / cs) and force (C sqrt(h / |a|max)).
StepLimits inertialLimits(const Simulation& sim);

} // namespace cementsph::sph
