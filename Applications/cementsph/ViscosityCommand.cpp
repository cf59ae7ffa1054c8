// cementsph viscosity: cement viscosity from a syringe pressure drop measured while pressing cement out
// through the cannula, by Hagen-Poiseuille (paper Eq. 13: mu = pi D^4 dP / (128 L Q)); or, given a
// viscosity, the pressure drop the cannula will take.
#include "CommandRegistry.h"

#include "cementsph/sph/HagenPoiseuille.h"

#include <cmath>
#include <iostream>
#include <stdexcept>

namespace {

struct ViscosityOptions {
  double pressureDropMPa = 0, viscosityPaS = 0;
  double diameterMm = 2.388, lengthMm = 90.0, flowRateMlPerS = 0.05; // the paper's 11G, 9 cm cannula
};

void requirePositive(double v, const char* option) {
  if (!(std::isfinite(v) && v > 0)) throw std::invalid_argument(std::string(option) + " must be positive");
}

int runViscosity(const ViscosityOptions& o) {
  requirePositive(o.diameterMm, "--cannula-inner-diameter-mm");
  requirePositive(o.lengthMm, "--cannula-length-mm");
  requirePositive(o.flowRateMlPerS, "--flow-rate-ml-per-s");
  const bool fromPressure = o.pressureDropMPa > 0, fromViscosity = o.viscosityPaS > 0;
  if (fromPressure == fromViscosity)
    throw std::invalid_argument("give exactly one of --pressure-drop-mpa (to get the viscosity) or --viscosity-pa-s");
  const double D = o.diameterMm * 1e-3, L = o.lengthMm * 1e-3, Q = o.flowRateMlPerS * 1e-6;
  if (fromPressure) {
    const double mu = cementsph::sph::hagenPoiseuilleViscosity(o.pressureDropMPa * 1e6, L, Q, D);
    std::cout << "viscosity_pa_s " << mu << "\n";
  } else {
    const double dP = cementsph::sph::hagenPoiseuillePressureDrop(o.viscosityPaS, L, Q, D);
    std::cout << "pressure_drop_mpa " << dP * 1e-6 << "\n";
  }
  std::cout << "bore_speed_mm_per_s " << cementsph::sph::boreSpeed(Q, D) * 1e3 << "\n";
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
  return [o] { return runViscosity(*o); };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(viscosity, "viscosity",
                           "Cement viscosity from a cannula pressure drop, or the drop from a viscosity (Eq. 13)",
                           setupViscosity)
