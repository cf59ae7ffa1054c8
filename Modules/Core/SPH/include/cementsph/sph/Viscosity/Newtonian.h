// Newtonian cement: every particle has the viscosity the run sets (Simulation::setViscosity; constant,
// the paper's linear rise with time, or a table: ViscositySchedule).
#pragma once

#include "cementsph/sph/ModelInterfaces.h"

namespace cementsph::sph {

class Newtonian : public ViscosityLaw {
public:
  std::string name() const override { return "newtonian"; }
  void update(Simulation& sim) override;
};

} // namespace cementsph::sph
