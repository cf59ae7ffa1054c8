#include "cementsph/sph/Viscosity/Newtonian.h"

#include "cementsph/sph/Simulation.h"

#include <algorithm>

namespace cementsph::sph {

void Newtonian::update(Simulation& sim) {
  FluidParticles& f = sim.fluid();
  std::fill(f.viscosity.begin(), f.viscosity.end(), sim.parameters().viscosity);
}

} // namespace cementsph::sph
