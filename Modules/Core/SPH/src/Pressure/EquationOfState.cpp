#include "cementsph/sph/Pressure/EquationOfState.h"

#include "cementsph/sph/Simulation.h"

namespace cementsph::sph {

void EquationOfState::density(Simulation& sim) { sim.sumDensity(); }

void EquationOfState::pressure(Simulation& sim) {
  FluidParticles& f = sim.fluid();
  const double cs2 = sim.parameters().soundSpeed * sim.parameters().soundSpeed, rho0 = sim.parameters().restDensity;
  const std::size_t n = f.size();
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) f.pressure[i] = cs2 * (f.density[i] - rho0); // Eq. 6
}

} // namespace cementsph::sph
