#include "cementsph/sph/Resistance/Permeability.h"

#include "cementsph/sph/Simulation.h"

#include <cmath>

namespace cementsph::sph {

void Permeability::update(Simulation& sim) {
  FluidParticles& f = sim.fluid();
  const ModelParameters& p = sim.parameters();
  const std::size_t n = f.size();
  // The medium is sampled where each particle is now (it moves through a varying field).
  for (std::size_t i = 0; i < n; ++i) {
    const Medium m = p.mediumField ? p.mediumField(f.position(i)) : p.medium;
    if (!(m.porosity > 0 && m.porosity <= 1) || !(m.permeability > 0) || !std::isfinite(m.permeability))
      throw SimulationError("permeability resistance: the medium at " + sim.describeParticleForModels(i) +
                            " has porosity " + std::to_string(m.porosity) + " and permeability " +
                            std::to_string(m.permeability) + " m^2 (need 0 < phi <= 1 and k > 0)");
    f.porosity[i] = m.porosity;
    f.permeability[i] = m.permeability;
    f.dragRate[i] = m.porosity * f.viscosity[i] / (f.density[i] * m.permeability);
  }
}

} // namespace cementsph::sph
