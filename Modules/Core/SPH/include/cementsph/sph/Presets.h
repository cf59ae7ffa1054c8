// Named parameter sets. "paper" follows Basafa et al. 2013 literally where it speaks (h = d/2 in the
// Darcy box, central-difference integration, cs = 1 m/s, rho0 = 1180 kg/m^3); "default" is ours, chosen
// by the convergence and calibration study recorded in VALIDATION.md. The paper gives no Cf: each
// preset carries one calibrated by the same rule (Kozeny-Carman at porosity 0.8).
#pragma once

#include "cementsph/sph/ModelParameters.h"

#include <string>
#include <vector>

namespace cementsph::sph {

struct ModelPreset {
  std::string name;
  std::string description;
  ModelParameters model;
  double hOverD; // smoothing length over particle spacing (Darcy box: spacing of the lattice)
};

ModelPreset modelPreset(const std::string& name); // throws std::invalid_argument for unknown names
std::vector<std::string> modelPresetNames();

} // namespace cementsph::sph
