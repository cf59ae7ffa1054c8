#include "cementsph/sph/Viscosity/Rheology.h"

#include "cementsph/sph/Viscosity/Carreau.h"
#include "cementsph/sph/Viscosity/PowerLaw.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cementsph::sph {

namespace {
class NewtonianRheology : public Rheology {
public:
  explicit NewtonianRheology(double mu) : mu_(mu) {}
  std::string name() const override { return "newtonian"; }
  double unbounded(double) const override { return mu_; }
  double flowIndex() const override { return 1.0; }

private:
  double mu_;
};

void requireIn(double x, double lo, double hi, const char* what) {
  if (!(x >= lo && x <= hi) || !std::isfinite(x))
    throw std::invalid_argument(std::string(what) + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                                "] (got " + std::to_string(x) + ")");
}
} // namespace

double Rheology::viscosity(double gammaDot) const {
  const double mu = unbounded(std::max(gammaDot, 0.0));
  if (std::isnan(mu)) return maximum; // 0^(n-1) with n < 1 is +inf, never NaN; kept safe anyway
  return std::clamp(mu, minimum, maximum);
}

double darcyShearRate(double q, double k, double phi, double n) {
  return (3.0 * n + 1.0) / (4.0 * n) * 12.0 * std::abs(q) / std::sqrt(150.0 * k * phi);
}

std::unique_ptr<Rheology> makeRheology(const std::string& name, const RheologyParameters& p) {
  requireIn(p.minimumViscosityPaS, 1e-9, 1e12, "viscosity_min_pa_s");
  requireIn(p.maximumViscosityPaS, p.minimumViscosityPaS, 1e12, "viscosity_max_pa_s (at least viscosity_min_pa_s)");
  std::unique_ptr<Rheology> law;
  // One line per law.
  if (name == "newtonian") {
    requireIn(p.viscosityPaS, 1e-9, 1e12, "viscosity_pa_s");
    law = std::make_unique<NewtonianRheology>(p.viscosityPaS);
  } else if (name == "power-law") {
    requireIn(p.consistencyPaSn, 1e-9, 1e12, "consistency_pa_s_n");
    requireIn(p.flowIndex, 0.05, 3.0, "flow_index");
    law = std::make_unique<PowerLaw>(p.consistencyPaSn, p.flowIndex);
  } else if (name == "carreau") {
    requireIn(p.zeroShearViscosityPaS, 1e-9, 1e12, "zero_shear_viscosity_pa_s");
    requireIn(p.infiniteShearViscosityPaS, 0.0, p.zeroShearViscosityPaS, "infinite_shear_viscosity_pa_s (at most the zero-shear one)");
    requireIn(p.timeConstantS, 0.0, 1e6, "carreau_time_constant_s");
    requireIn(p.flowIndex, 0.05, 3.0, "flow_index");
    law = std::make_unique<Carreau>(p.zeroShearViscosityPaS, p.infiniteShearViscosityPaS, p.timeConstantS, p.flowIndex);
  } else {
    throw std::invalid_argument("unknown viscosity law '" + name + "' (newtonian, power-law or carreau)");
  }
  law->minimum = p.minimumViscosityPaS;
  law->maximum = p.maximumViscosityPaS;
  return law;
}

} // namespace cementsph::sph
