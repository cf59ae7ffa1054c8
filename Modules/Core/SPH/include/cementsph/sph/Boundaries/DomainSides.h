// The box's sides: periodic axes re-enter a particle on the opposite side with its velocity and density
// (the paper, after Jiang et al.); a particle that crosses an open side leaves the simulation (counted).
#pragma once

#include "cementsph/sph/ModelInterfaces.h"

namespace cementsph::sph {

class DomainSides : public DomainBoundary {
public:
  std::string name() const override { return "domain-sides"; }
  std::size_t apply(Simulation& sim) override;
};

} // namespace cementsph::sph
