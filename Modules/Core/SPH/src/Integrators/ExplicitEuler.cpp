#include "cementsph/sph/Integrators/Integrators.h"

#include "cementsph/sph/Simulation.h"

#include <algorithm>

namespace cementsph::sph {

StepLimits ExplicitEuler::limits(const Simulation& sim) const {
  const ModelParameters& p = sim.parameters();
  StepLimits l = inertialLimits(sim);
  if (p.viscosityModel == ViscosityModel::Morris) {
    const auto& mu = sim.fluid().viscosity;
    const double muMax = mu.empty() ? p.viscosity : *std::max_element(mu.begin(), mu.end());
    l.viscous = p.viscousNumber * p.smoothingLength * p.smoothingLength * p.restDensity / muMax;
  }
  const double g = sim.maxDragRate();
  if (g > 0) l.drag = 1.0 / g;
  return l;
}

void ExplicitEuler::integrate(Simulation& sim, double dt) {
  FluidParticles& f = sim.fluid();
  const std::size_t n = f.size();
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    const double g = f.dragRate[i];
    f.vx[i] += dt * (f.ax[i] - g * f.vx[i]);
    f.vy[i] += dt * (f.ay[i] - g * f.vy[i]);
    f.vz[i] += dt * (f.az[i] - g * f.vz[i]);
    f.xp[i] = f.x[i]; f.yp[i] = f.y[i]; f.zp[i] = f.z[i];
    f.x[i] += dt * f.vx[i]; f.y[i] += dt * f.vy[i]; f.z[i] += dt * f.vz[i];
  }
}

} // namespace cementsph::sph
