#include "cementsph/sph/Presets.h"

#include <stdexcept>

namespace cementsph::sph {

ModelPreset modelPreset(const std::string& name) {
  ModelPreset p;
  p.name = name;
  p.model.restDensity = 1180.0;
  p.model.soundSpeed = 1.0;
  p.model.viscosityModel = ViscosityModel::Drag;
  if (name == "default") {
    p.description = "h = 1.0 d (lattice density within 3e-5 of rho0, 26 neighbours), overdamped integration, "
                    "Cf calibrated to Kozeny-Carman over porosity 0.7-0.9";
    p.hOverD = 1.0;
    p.model.integrator = Integrator::Overdamped;
    p.model.dragCoefficient = 1.0;
  } else if (name == "paper") {
    p.description = "Basafa et al. 2013 literally: h = d/2, central-difference integration (Eq. 8) with implicit "
                    "drag (Eq. 9); Cf calibrated like the default (the paper gives none)";
    p.hOverD = 0.5;
    p.model.integrator = Integrator::CentralDifference;
    p.model.dragCoefficient = 1.0;
  } else {
    throw std::invalid_argument("unknown preset '" + name + "' (expected default or paper)");
  }
  return p;
}

std::vector<std::string> modelPresetNames() { return {"default", "paper"}; }

} // namespace cementsph::sph
