// The paper's drag (Basafa et al. 2013, Eq. 9): a_i = -gamma_i v_i with gamma_i = Cf m_i mu_i / (rho_i^2 h^5),
// a particle's own velocity only. In free space it is a Darcy medium of permeability k0 = h^5 / (Cf d^3)
// (model-notes 3); with fixed particles the pores' geometry adds the rest (cementsph darcy measures it).
#pragma once

#include "cementsph/sph/ModelInterfaces.h"

namespace cementsph::sph {

class PaperDrag : public Resistance {
public:
  std::string name() const override { return "paper-drag"; }
  void update(Simulation& sim) override;
};

// No resistance (inviscid tests, Morris viscosity).
class NoResistance : public Resistance {
public:
  std::string name() const override { return "none"; }
  void update(Simulation& sim) override;
};

} // namespace cementsph::sph
