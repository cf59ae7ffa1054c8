#include "cementsph/rheology/HagenPoiseuille.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace cementsph::rheology {

namespace {

constexpr double kPi = 3.14159265358979323846;

void requirePositive(double v, const char* what) {
  if (!(std::isfinite(v) && v > 0))
    throw std::invalid_argument(std::string("Hagen-Poiseuille: ") + what + " must be positive and finite");
}
} // namespace

double hagenPoiseuillePressureDrop(double viscosityPaS, double lengthM, double flowRateM3PerS, double diameterM) {
  requirePositive(viscosityPaS, "viscosity");
  requirePositive(lengthM, "length");
  requirePositive(flowRateM3PerS, "flow rate");
  requirePositive(diameterM, "diameter");
  const double d2 = diameterM * diameterM;
  return 128.0 * viscosityPaS * lengthM * flowRateM3PerS / (kPi * d2 * d2);
}

double hagenPoiseuilleViscosity(double pressureDropPa, double lengthM, double flowRateM3PerS, double diameterM) {
  requirePositive(pressureDropPa, "pressure drop");
  requirePositive(lengthM, "length");
  requirePositive(flowRateM3PerS, "flow rate");
  requirePositive(diameterM, "diameter");
  const double d2 = diameterM * diameterM;
  return kPi * d2 * d2 * pressureDropPa / (128.0 * lengthM * flowRateM3PerS); // Eq. 13
}

double boreSpeed(double flowRateM3PerS, double diameterM) {
  requirePositive(flowRateM3PerS, "flow rate");
  requirePositive(diameterM, "diameter");
  return flowRateM3PerS / (0.25 * kPi * diameterM * diameterM);
}

} // namespace cementsph::rheology
