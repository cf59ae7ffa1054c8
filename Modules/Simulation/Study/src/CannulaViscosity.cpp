#include "cementsph/study/CannulaViscosity.h"

#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/TubeFlow.h"

#include <cmath>
#include <stdexcept>

namespace cementsph::study {

namespace {

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

void checkRequest(const CannulaViscosityRequest& o, double diameterMm) {
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
}

} // namespace

CannulaViscosityResult cannulaViscosity(const CannulaViscosityRequest& o) {
  CannulaViscosityResult r;
  r.diameterMm = o.gauge.empty() ? o.diameterMm : sph::cannulaInnerDiameterMm(o.gauge);
  checkRequest(o, r.diameterMm);
  r.powerLaw = o.flowIndex != 0 || o.consistencyPaSn != 0;
  r.fromPressure = o.pressureDropMPa > 0;
  r.lengthMm = o.lengthMm;
  r.flowRateMlPerS = o.flowRateMlPerS;
  if (!o.gauge.empty()) r.gauge = sph::canonicalCannulaGauge(o.gauge);
  // SI for the formulas.
  const double D = r.diameterMm * 1e-3, L = o.lengthMm * 1e-3, Q = o.flowRateMlPerS * 1e-6;
  r.boreSpeedMmPerS = sph::boreSpeed(Q, D) * 1e3;
  r.pressureDropPa = o.pressureDropMPa * 1e6;
  double answer = 0; // the viscosity or K
  if (r.powerLaw) {
    r.flowIndex = o.flowIndex;
    answer = r.fromPressure ? sph::powerLawConsistency(r.pressureDropPa, o.flowIndex, L, Q, D) : o.consistencyPaSn;
    if (!r.fromPressure) r.pressureDropPa = sph::powerLawTubePressureDrop(answer, o.flowIndex, L, Q, D);
    r.consistencyPaSn = answer;
  } else {
    answer = r.fromPressure ? sph::hagenPoiseuilleViscosity(r.pressureDropPa, L, Q, D) : o.viscosityPaS;
    if (!r.fromPressure) r.pressureDropPa = sph::hagenPoiseuillePressureDrop(answer, L, Q, D);
    r.viscosityPaS = answer;
  }
  const char* inputs = r.fromPressure ? "--pressure-drop-mpa, --flow-rate-ml-per-s and the cannula size"
                       : r.powerLaw   ? "--consistency-pa-s-n, --flow-index, --flow-rate-ml-per-s and the cannula size"
                                      : "--viscosity-pa-s, --flow-rate-ml-per-s and the cannula size";
  requireFiniteResult(r.pressureDropPa, "the pressure drop", inputs);
  requireFiniteResult(r.boreSpeedMmPerS, "the bore speed", "--flow-rate-ml-per-s and the cannula size");
  requireFiniteResult(answer, r.powerLaw ? "the consistency" : "the viscosity", inputs);
  return r;
}

nlohmann::json CannulaViscosityResult::toJson() const {
  nlohmann::json j{{"law", powerLaw ? "power-law" : "newtonian"},
                   {"cannula_inner_diameter_mm", diameterMm},
                   {"cannula_length_mm", lengthMm},
                   {"flow_rate_ml_per_s", flowRateMlPerS},
                   {"bore_speed_mm_per_s", boreSpeedMmPerS}};
  if (gauge) j["cannula_gauge"] = *gauge;
  if (powerLaw) {
    j["flow_index"] = *flowIndex;
    j["consistency_pa_s_n"] = *consistencyPaSn;
  } else {
    j["viscosity_pa_s"] = *viscosityPaS;
  }
  j["pressure_drop_pa"] = pressureDropPa;
  j["pressure_drop_mpa"] = pressureDropPa * 1e-6;
  return j;
}

} // namespace cementsph::study
