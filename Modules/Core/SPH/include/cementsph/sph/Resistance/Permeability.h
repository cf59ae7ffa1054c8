// Darcy's law in a continuum medium (bone whose pores the CT does not resolve): the superficial velocity
// is u = -(k / mu) grad p and the cement moves at the interstitial velocity v = u / phi. With the
// engine's acceleration a = -grad p / rho, a = gamma v gives gamma_i = phi_i mu_i / (rho_i k_i).
// phi and k come from ModelParameters::mediumField at the particle (or the uniform ModelParameters::medium)
// and are kept in fluid().porosity / fluid().permeability.
#pragma once

#include "cementsph/sph/ModelInterfaces.h"

namespace cementsph::sph {

class Permeability : public Resistance {
public:
  std::string name() const override { return "permeability"; }
  void update(Simulation& sim) override;
};

} // namespace cementsph::sph
