// Every method of this build, by name: adding a model is its file and one line here.
#include "cementsph/sph/ModelRegistry.h"

#include "cementsph/sph/Boundaries/DomainSides.h"
#include "cementsph/sph/Integrators/Integrators.h"
#include "cementsph/sph/ModelParameters.h"
#include "cementsph/sph/Pressure/EquationOfState.h"
#include "cementsph/sph/Pressure/IncompressibleDarcy.h"
#include "cementsph/sph/Resistance/PaperDrag.h"
#include "cementsph/sph/Resistance/Permeability.h"
#include "cementsph/sph/Viscosity/Newtonian.h"

#include <algorithm>

namespace cementsph::sph {

double StepLimits::stable() const { return std::min({acoustic, viscous, drag, force, overdamped}); }

namespace {
template <class T> auto make() {
  return [](const ModelParameters&) { return std::make_unique<T>(); };
}
} // namespace

const ModelRegistry& ModelRegistry::instance() {
  static const ModelRegistry registry = [] {
    ModelRegistry r;
    r.pressure.add("equation-of-state", make<EquationOfState>());               // Eq. 6
    r.pressure.add("incompressible", [](const ModelParameters& p) {             // Darcy pressure solve
      return std::make_unique<IncompressibleDarcy>(p);
    });
    r.resistance.add("paper-drag", make<PaperDrag>());                          // Eq. 9
    r.resistance.add("permeability", make<Permeability>());                     // k / (phi mu)
    r.resistance.add("none", make<NoResistance>());
    r.viscosity.add("newtonian", make<Newtonian>());
    r.integrator.add("central-difference", make<CentralDifference>());          // Eq. 8
    r.integrator.add("explicit", make<ExplicitEuler>());
    r.integrator.add("overdamped", make<Overdamped>());
    r.boundary.add("domain-sides", make<DomainSides>());
    return r;
  }();
  return registry;
}

} // namespace cementsph::sph
