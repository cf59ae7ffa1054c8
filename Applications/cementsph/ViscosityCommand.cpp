// cementsph viscosity: cement viscosity from a syringe pressure drop measured while pressing cement out
// through the cannula, by Hagen-Poiseuille (paper Eq. 13: mu = pi D^4 dP / (128 L Q)); or, given a
// viscosity, the pressure drop the cannula will take. With --flow-index n the cement is a power law
// (consistency K in Pa.s^n): the drop by Rabinowitsch-Mooney (exact), or K from a measured drop at that n
// (TubeFlow.h). --cannula-gauge picks the inner diameter from the gauge table; --json prints one object.
// A thin layer: the units, checks, formulas and the JSON object are CementSPH::Study's (CannulaViscosity.h).
#include "CommandRegistry.h"

#include "cementsph/sph/TubeFlow.h"
#include "cementsph/study/CannulaViscosity.h"

#include <cstdlib>
#include <stdexcept>
#include <iostream>

namespace {

struct ViscosityOptions {
  cementsph::study::CannulaViscosityRequest request;
  bool json = false;
};

int runViscosity(const ViscosityOptions& o) {
  const cementsph::study::CannulaViscosityResult r = cementsph::study::cannulaViscosity(o.request);
  if (o.json) {
    std::cout << r.toJson().dump(2) << "\n";
    return 0;
  }
  if (r.fromPressure) std::cout << (r.powerLaw ? "consistency_pa_s_n " : "viscosity_pa_s ")
                                << (r.powerLaw ? *r.consistencyPaSn : *r.viscosityPaS) << "\n";
  else std::cout << "pressure_drop_mpa " << r.pressureDropPa * 1e-6 << "\n";
  std::cout << "bore_speed_mm_per_s " << r.boreSpeedMmPerS << "\n";
  return 0;
}

cementsph::app::CommandRunner setupViscosity(CLI::App& sub) {
  auto o = std::make_shared<ViscosityOptions>();
  sub.add_option("--pressure-drop-mpa", o->request.pressureDropMPa, "measured pressure drop along the cannula [MPa]");
  sub.add_option("--viscosity-pa-s", o->request.viscosityPaS, "cement viscosity [Pa.s] (prints the pressure drop instead)");
  sub.add_option("--cannula-inner-diameter-mm", o->request.diameterMm, "inner diameter [mm] (11G regular wall: 2.388)")
      ->capture_default_str();
  sub.add_option("--cannula-length-mm", o->request.lengthMm, "cannula length [mm]")->capture_default_str();
  sub.add_option("--flow-rate-ml-per-s", o->request.flowRateMlPerS, "flow rate [ml/s]")->capture_default_str();
  sub.add_option("--consistency-pa-s-n", o->request.consistencyPaSn, "power-law consistency K [Pa.s^n] (prints the drop)");
  sub.add_option("--flow-index", o->request.flowIndex, "power-law flow index n (with --consistency-pa-s-n or --pressure-drop-mpa)");
  sub.add_option("--cannula-gauge", o->request.gauge,
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
  // An unknown gauge is refused while the options are read, the line naming --cannula-gauge (the table's own
  // message named no option).
  sub.get_option("--cannula-gauge")->check(CLI::Validator(
      [](std::string& value) -> std::string {
        try {
          (void)cementsph::sph::cannulaInnerDiameterMm(value);
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
        return {};
      },
      "", "a known gauge"));
  // The gauge sets the diameter: both given, one was silently ignored.
  sub.get_option("--cannula-gauge")->excludes("--cannula-inner-diameter-mm");
  return [o] { return runViscosity(*o); };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(viscosity, "viscosity",
                           "Cement viscosity (Eq. 13) or power-law consistency from a cannula pressure drop, or the drop",
                           setupViscosity)
