#include "cementsph/sph/Integrators/Integrators.h"

#include "cementsph/sph/Simulation.h"

#include <algorithm>
#include <cmath>

namespace cementsph::sph {

StepLimits inertialLimits(const Simulation& sim) {
  const ModelParameters& p = sim.parameters();
  const FluidParticles& f = sim.fluid();
  const double h = p.smoothingLength;
  StepLimits l;
  if (sim.pressureModel().acoustic()) l.acoustic = p.acousticCourant * h / p.soundSpeed;
  double amax2 = 0;
  const std::size_t n = f.size();
#pragma omp parallel for schedule(static) reduction(max : amax2) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) amax2 = std::max(amax2, f.ax[i] * f.ax[i] + f.ay[i] * f.ay[i] + f.az[i] * f.az[i]);
  if (amax2 > 0) l.force = p.forceCourant * std::sqrt(h / std::sqrt(amax2));
  return l;
}

StepLimits CentralDifference::limits(const Simulation& sim) const { return inertialLimits(sim); }

void CentralDifference::integrate(Simulation& sim, double dt) {
  // Eq. 8 with a_i = a_other - gamma v_i and v_i = (r+ - r-) / (2 dt), solved for r+ per particle.
  FluidParticles& f = sim.fluid();
  const std::size_t n = f.size();
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    const double gdt2 = 0.5 * dt * f.dragRate[i];
    const double inv = 1.0 / (1.0 + gdt2), c = 1.0 - gdt2, dt2 = dt * dt;
    const double nx = (2 * f.x[i] - c * f.xp[i] + dt2 * f.ax[i]) * inv;
    const double ny = (2 * f.y[i] - c * f.yp[i] + dt2 * f.ay[i]) * inv;
    const double nz = (2 * f.z[i] - c * f.zp[i] + dt2 * f.az[i]) * inv;
    f.vx[i] = (nx - f.xp[i]) / (2 * dt);
    f.vy[i] = (ny - f.yp[i]) / (2 * dt);
    f.vz[i] = (nz - f.zp[i]) / (2 * dt);
    f.xp[i] = f.x[i]; f.yp[i] = f.y[i]; f.zp[i] = f.z[i];
    f.x[i] = nx; f.y[i] = ny; f.z[i] = nz;
  }
}

} // namespace cementsph::sph
