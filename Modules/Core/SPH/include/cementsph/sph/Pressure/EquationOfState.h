// The paper's weakly compressible pressure: density by summation over fluid and fixed particles (Eq. 2),
// p = cs^2 (rho - rho0) (Eq. 6). Assumes the flow's pressures stay well below rho0 cs^2 (1.18 kPa at the
// paper's cs = 1 m/s); where they do not (a viscous cement in bone), the cement is compressed and the
// pressure saturates (docs/architecture.md, "Choosing a model").
#pragma once

#include "cementsph/sph/ModelInterfaces.h"

namespace cementsph::sph {

class EquationOfState : public PressureModel {
public:
  std::string name() const override { return "equation-of-state"; }
  void density(Simulation& sim) override;
  void pressure(Simulation& sim) override;
};

} // namespace cementsph::sph
