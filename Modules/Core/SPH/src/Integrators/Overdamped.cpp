#include "cementsph/sph/Integrators/Integrators.h"

#include "cementsph/sph/Simulation.h"

#include <algorithm>
#include <cmath>

namespace cementsph::sph {

StepLimits Overdamped::limits(const Simulation& sim) const {
  const ModelParameters& p = sim.parameters();
  const FluidParticles& f = sim.fluid();
  const double h = p.smoothingLength;
  StepLimits l;
  if (sim.pressureModel().acoustic())
    l.overdamped = p.overdampedStability * sim.minDragRate() * h * h / (p.soundSpeed * p.soundSpeed);
  // v = a / gamma; the fastest particle bounds the step for accuracy.
  double vmax2 = 0;
  const std::size_t n = f.size();
#pragma omp parallel for schedule(static) reduction(max : vmax2) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    const double g = f.dragRate[i];
    const double a2 = f.ax[i] * f.ax[i] + f.ay[i] * f.ay[i] + f.az[i] * f.az[i];
    vmax2 = std::max(vmax2, a2 / (g * g));
  }
  if (vmax2 > 0) l.displacement = p.maxDisplacement * h / std::sqrt(vmax2);
  return l;
}

void Overdamped::integrate(Simulation& sim, double dt) {
  FluidParticles& f = sim.fluid();
  const std::size_t n = f.size();
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    const double invG = 1.0 / f.dragRate[i];
    f.vx[i] = f.ax[i] * invG; f.vy[i] = f.ay[i] * invG; f.vz[i] = f.az[i] * invG;
    f.xp[i] = f.x[i]; f.yp[i] = f.y[i]; f.zp[i] = f.z[i];
    f.x[i] += dt * f.vx[i]; f.y[i] += dt * f.vy[i]; f.z[i] += dt * f.vz[i];
  }
}

} // namespace cementsph::sph
