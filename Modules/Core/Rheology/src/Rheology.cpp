#include "cementsph/rheology/Rheology.h"

#include "cementsph/rheology/Carreau.h"
#include "cementsph/rheology/PowerLaw.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace cementsph::rheology {

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

namespace {

using LawFactory = std::unique_ptr<Rheology> (*)(const RheologyParameters&);

std::unique_ptr<Rheology> newtonian(const RheologyParameters& p) {
  requireIn(p.viscosityPaS, 1e-9, 1e12, "viscosity_pa_s");
  return std::make_unique<NewtonianRheology>(p.viscosityPaS);
}

std::unique_ptr<Rheology> powerLaw(const RheologyParameters& p) {
  requireIn(p.consistencyPaSn, 1e-9, 1e12, "consistency_pa_s_n");
  requireIn(p.flowIndex, 0.05, 3.0, "flow_index");
  return std::make_unique<PowerLaw>(p.consistencyPaSn, p.flowIndex);
}

std::unique_ptr<Rheology> carreau(const RheologyParameters& p) {
  requireIn(p.zeroShearViscosityPaS, 1e-9, 1e12, "zero_shear_viscosity_pa_s");
  requireIn(p.infiniteShearViscosityPaS, 0.0, p.zeroShearViscosityPaS, "infinite_shear_viscosity_pa_s (at most the zero-shear one)");
  requireIn(p.timeConstantS, 0.0, 1e6, "carreau_time_constant_s");
  requireIn(p.flowIndex, 0.05, 3.0, "flow_index");
  return std::make_unique<Carreau>(p.zeroShearViscosityPaS, p.infiniteShearViscosityPaS, p.timeConstantS, p.flowIndex);
}

// The law registry, shared by both engines: one line per law (its class in its own header, PowerLaw.h, ...).
const std::vector<std::pair<std::string, LawFactory>>& laws() {
  static const std::vector<std::pair<std::string, LawFactory>> table = {
      {"newtonian", newtonian},
      {"power-law", powerLaw},
      {"carreau", carreau},
  };
  return table;
}

} // namespace

std::vector<std::string> rheologyNames() {
  std::vector<std::string> names;
  for (const auto& law : laws()) names.push_back(law.first);
  return names;
}

std::unique_ptr<Rheology> makeRheology(const std::string& name, const RheologyParameters& p) {
  requireIn(p.minimumViscosityPaS, 1e-9, 1e12, "viscosity_min_pa_s");
  requireIn(p.maximumViscosityPaS, p.minimumViscosityPaS, 1e12, "viscosity_max_pa_s (at least viscosity_min_pa_s)");
  std::unique_ptr<Rheology> law;
  std::string known;
  for (const auto& [lawName, factory] : laws()) {
    if (lawName == name) law = factory(p);
    known += (known.empty() ? "" : ", ") + lawName;
  }
  if (!law) throw std::invalid_argument("unknown viscosity law '" + name + "' (" + known + ")");
  law->minimum = p.minimumViscosityPaS;
  law->maximum = p.maximumViscosityPaS;
  return law;
}

} // namespace cementsph::rheology
