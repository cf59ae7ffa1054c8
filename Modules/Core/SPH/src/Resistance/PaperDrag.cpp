#include "cementsph/sph/Resistance/PaperDrag.h"

#include "cementsph/sph/Simulation.h"

namespace cementsph::sph {

void PaperDrag::update(Simulation& sim) {
  FluidParticles& f = sim.fluid();
  const ModelParameters& p = sim.parameters();
  const std::size_t n = f.size();
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) f.dragRate[i] = p.dragRate(f.mass[i], f.density[i], f.viscosity[i]); // Eq. 9
}

void NoResistance::update(Simulation& sim) {
  FluidParticles& f = sim.fluid();
  std::fill(f.dragRate.begin(), f.dragRate.end(), 0.0);
}

} // namespace cementsph::sph
