// What `cementsph viscosity` computes: a cement's viscosity from the syringe pressure drop measured while pressing
// it out through the cannula, by Hagen-Poiseuille (Basafa et al. 2013, Eq. 13: mu = pi D^4 dP / (128 L Q)), or,
// given a viscosity, the drop the cannula will take; with a flow index n the cement is a power law (consistency
// K in Pa.s^n): the drop by Rabinowitsch-Mooney, or K from a measured drop (CementSPH::SPH's TubeFlow.h and
// HagenPoiseuille.h hold the formulas). Here: the units of the options, which law and direction they ask for,
// the checks, and the --json object's schema, so the command only parses options and prints.
#pragma once

#include <nlohmann/json.hpp>

#include <optional>
#include <string>

namespace cementsph::study {

// The options, in their units. 0 stands for "not given" in the four that choose the mode.
struct CannulaViscosityRequest {
  double pressureDropMPa = 0, viscosityPaS = 0, consistencyPaSn = 0, flowIndex = 0;
  double diameterMm = 2.388, lengthMm = 90.0, flowRateMlPerS = 0.05; // the paper's 11G, 9 cm cannula
  std::string gauge; // a gauge name instead of the diameter (TubeFlow.h's table)
};

struct CannulaViscosityResult {
  bool powerLaw = false;    // a power-law cement (a flow index was given)
  bool fromPressure = false; // the drop was measured: the viscosity (or K) is the answer
  double diameterMm = 0, lengthMm = 0, flowRateMlPerS = 0, boreSpeedMmPerS = 0, pressureDropPa = 0;
  std::optional<std::string> gauge;           // canonical name, when given by gauge
  std::optional<double> viscosityPaS;         // Newtonian
  std::optional<double> consistencyPaSn, flowIndex; // power law
  // The --json object: law, cannula_inner_diameter_mm, cannula_length_mm, flow_rate_ml_per_s,
  // bore_speed_mm_per_s, cannula_gauge (when given), viscosity_pa_s or flow_index and consistency_pa_s_n,
  // pressure_drop_pa, pressure_drop_mpa.
  nlohmann::json toJson() const;
};

// Throws std::invalid_argument naming the option (as the command line spells it) for a value out of range, a
// mode given twice or not at all, and a result that is not a finite positive number.
CannulaViscosityResult cannulaViscosity(const CannulaViscosityRequest& request);

} // namespace cementsph::study
