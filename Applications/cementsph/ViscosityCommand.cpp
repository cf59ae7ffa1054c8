// cementsph viscosity: cement viscosity from a syringe pressure drop measured while pressing cement out
// through the cannula, by Hagen-Poiseuille (paper Eq. 13: mu = pi D^4 dP / (128 L Q)); or, given a
// viscosity, the pressure drop the cannula will take. With --flow-index n the cement is a power law
// (consistency K in Pa.s^n): the drop by Rabinowitsch-Mooney (exact), or K from a measured drop at that n
// (TubeFlow.h). --cannula-gauge picks the inner diameter from the gauge table; --json prints one object.
#include "CommandRegistry.h"

#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/TubeFlow.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <stdexcept>

namespace {

struct ViscosityOptions {
  double pressureDropMPa = 0, viscosityPaS = 0, consistencyPaSn = 0, flowIndex = 0;
  double diameterMm = 2.388, lengthMm = 90.0, flowRateMlPerS = 0.05; // the paper's 11G, 9 cm cannula
  std::string gauge;
  bool json = false;
};

void requirePositive(double v, const char* option) {
  if (!(std::isfinite(v) && v > 0)) throw std::invalid_argument(std::string(option) + " must be positive");
}

// A value option given: finite and >= 0 (0 is "not given"). NaN would otherwise count as "not given".
void requireFiniteOrUnset(double v, const char* option) {
  if (!(std::isfinite(v) && v >= 0))
    throw std::invalid_argument(std::string(option) + " must be a finite number > 0");
}

// A result must be a finite positive number: options each within range can still overflow together
// (a drop of 1e300 MPa over a 1e-300 ml/s flow), and an `inf` printed (or `null` in --json) is no answer.
void requireFiniteResult(double v, const char* what, const char* options) {
  if (!(std::isfinite(v) && v > 0))
    throw std::invalid_argument(std::string(what) + " comes out as " + (std::isnan(v) ? "undefined" : v > 0 ? "infinite" : "not positive") +
                                " for these options: " + options + " are outside what a cannula and cement can give; check their values and units");
}

int runViscosity(const ViscosityOptions& o) {
  const double diameterMm = o.gauge.empty() ? o.diameterMm : cementsph::sph::cannulaInnerDiameterMm(o.gauge);
  requirePositive(diameterMm, "--cannula-inner-diameter-mm");
  requirePositive(o.lengthMm, "--cannula-length-mm");
  requirePositive(o.flowRateMlPerS, "--flow-rate-ml-per-s");
  requireFiniteOrUnset(o.pressureDropMPa, "--pressure-drop-mpa");
  requireFiniteOrUnset(o.viscosityPaS, "--viscosity-pa-s");
  requireFiniteOrUnset(o.consistencyPaSn, "--consistency-pa-s-n");
  requireFiniteOrUnset(o.flowIndex, "--flow-index");
  const bool powerLaw = o.flowIndex != 0 || o.consistencyPaSn != 0;
  if (powerLaw && !(o.flowIndex > 0 && o.flowIndex <= 3))
    throw std::invalid_argument("--flow-index must be in (0, 3] (a power-law cement needs it)");
  const bool fromPressure = o.pressureDropMPa > 0;
  const bool fromLaw = powerLaw ? o.consistencyPaSn > 0 : o.viscosityPaS > 0;
  if (fromPressure == fromLaw || (powerLaw && o.viscosityPaS > 0))
    throw std::invalid_argument(powerLaw ? "give exactly one of --pressure-drop-mpa (to get K) or --consistency-pa-s-n, with --flow-index"
                                         : "give exactly one of --pressure-drop-mpa (to get the viscosity) or --viscosity-pa-s");
  const double D = diameterMm * 1e-3, L = o.lengthMm * 1e-3, Q = o.flowRateMlPerS * 1e-6;
  nlohmann::json j{{"law", powerLaw ? "power-law" : "newtonian"},
                   {"cannula_inner_diameter_mm", diameterMm},
                   {"cannula_length_mm", o.lengthMm},
                   {"flow_rate_ml_per_s", o.flowRateMlPerS},
                   {"bore_speed_mm_per_s", cementsph::sph::boreSpeed(Q, D) * 1e3}};
  if (!o.gauge.empty()) j["cannula_gauge"] = cementsph::sph::canonicalCannulaGauge(o.gauge);
  double dropPa = o.pressureDropMPa * 1e6;
  if (powerLaw) {
    j["flow_index"] = o.flowIndex;
    const double K = fromPressure ? cementsph::sph::powerLawConsistency(dropPa, o.flowIndex, L, Q, D) : o.consistencyPaSn;
    if (!fromPressure) dropPa = cementsph::sph::powerLawTubePressureDrop(K, o.flowIndex, L, Q, D);
    j["consistency_pa_s_n"] = K;
  } else {
    const double mu = fromPressure ? cementsph::sph::hagenPoiseuilleViscosity(dropPa, L, Q, D) : o.viscosityPaS;
    if (!fromPressure) dropPa = cementsph::sph::hagenPoiseuillePressureDrop(mu, L, Q, D);
    j["viscosity_pa_s"] = mu;
  }
  const char* inputs = fromPressure ? "--pressure-drop-mpa, --flow-rate-ml-per-s and the cannula size"
                                    : powerLaw ? "--consistency-pa-s-n, --flow-index, --flow-rate-ml-per-s and the cannula size"
                                               : "--viscosity-pa-s, --flow-rate-ml-per-s and the cannula size";
  requireFiniteResult(dropPa, "the pressure drop", inputs);
  requireFiniteResult(j["bore_speed_mm_per_s"].get<double>(), "the bore speed", "--flow-rate-ml-per-s and the cannula size");
  requireFiniteResult(powerLaw ? j["consistency_pa_s_n"].get<double>() : j["viscosity_pa_s"].get<double>(),
                      powerLaw ? "the consistency" : "the viscosity", inputs);
  j["pressure_drop_pa"] = dropPa;
  j["pressure_drop_mpa"] = dropPa * 1e-6;
  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  if (fromPressure) std::cout << (powerLaw ? "consistency_pa_s_n " : "viscosity_pa_s ")
                              << (powerLaw ? j["consistency_pa_s_n"] : j["viscosity_pa_s"]).get<double>() << "\n";
  else std::cout << "pressure_drop_mpa " << dropPa * 1e-6 << "\n";
  std::cout << "bore_speed_mm_per_s " << j["bore_speed_mm_per_s"].get<double>() << "\n";
  return 0;
}

cementsph::app::CommandRunner setupViscosity(CLI::App& sub) {
  auto o = std::make_shared<ViscosityOptions>();
  sub.add_option("--pressure-drop-mpa", o->pressureDropMPa, "measured pressure drop along the cannula [MPa]");
  sub.add_option("--viscosity-pa-s", o->viscosityPaS, "cement viscosity [Pa.s] (prints the pressure drop instead)");
  sub.add_option("--cannula-inner-diameter-mm", o->diameterMm, "inner diameter [mm] (11G regular wall: 2.388)")
      ->capture_default_str();
  sub.add_option("--cannula-length-mm", o->lengthMm, "cannula length [mm]")->capture_default_str();
  sub.add_option("--flow-rate-ml-per-s", o->flowRateMlPerS, "flow rate [ml/s]")->capture_default_str();
  sub.add_option("--consistency-pa-s-n", o->consistencyPaSn, "power-law consistency K [Pa.s^n] (prints the drop)");
  sub.add_option("--flow-index", o->flowIndex, "power-law flow index n (with --consistency-pa-s-n or --pressure-drop-mpa)");
  sub.add_option("--cannula-gauge", o->gauge,
                 "cannula gauge instead of the inner diameter (nominal, TubeFlow.h): " +
                     cementsph::sph::knownCannulaGauges() + "; thin wall also as 10GTW");
  sub.add_flag("--json", o->json, "print one JSON object (pressure_drop_pa, ...)");
  // 0 stands for "not given" in these four, so a 0 typed by the user silently chose another mode
  // (`--pressure-drop-mpa 1 --flow-index 0` printed a Newtonian viscosity): given, they must be positive.
  for (const char* name : {"--pressure-drop-mpa", "--viscosity-pa-s", "--consistency-pa-s-n", "--flow-index"})
    sub.get_option(name)->check(CLI::Validator(
        [](std::string& value) -> std::string {
          char* end = nullptr;
          if (!(std::strtod(value.c_str(), &end) > 0)) return "must be positive (got '" + value.substr(0, 40) + "')";
          return {};
        },
        "", "positive"));
  // The gauge sets the diameter: both given, one was silently ignored.
  sub.get_option("--cannula-gauge")->excludes("--cannula-inner-diameter-mm");
  return [o] { return runViscosity(*o); };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(viscosity, "viscosity",
                           "Cement viscosity (Eq. 13) or power-law consistency from a cannula pressure drop, or the drop",
                           setupViscosity)
