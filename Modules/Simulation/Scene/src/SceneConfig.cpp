#include "cementsph/scene/SceneConfig.h"

#include "cementsph/sph/TubeFlow.h"

#include "cementsph/sph/ModelParameters.h"
#include "cementsph/sph/Presets.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace cementsph::scene {

namespace {

using nlohmann::json;

// A value from a scene or the command line, echoed in a message: at most 40 characters and no control
// characters, so a 50 MB value (or one with newlines) still gives one readable line.
std::string shown(const std::string& value) {
  std::string out;
  for (unsigned char c : value) {
    if (out.size() >= 40) return out + "...";
    out += (c < 32 || c == 127) ? '?' : char(c);
  }
  return out;
}

[[noreturn]] void fail(const std::string& key, const std::string& what) {
  throw std::invalid_argument("scene: key '" + shown(key) + "' " + what);
}

// A number's physical range, one line naming the key, the value and limit in the key's unit, why the limit is
// where it is, and what to do: "scene: key 'volume_ml' is too large: 2000 ml is above 1000 ml (a vertebral body
// holds 30-50 ml): give the volume in ml". NaN fails both.
void requireAtLeast(double value, double limit, const char* key, const char* unit, const char* why, const char* advice) {
  if (value >= limit) return;
  std::ostringstream what;
  what << "is too small: " << value << " " << unit << " is below " << limit << " " << unit << " (" << why << "): " << advice;
  fail(key, what.str());
}

void requireAtMost(double value, double limit, const char* key, const char* unit, const char* why, const char* advice) {
  if (value <= limit) return;
  std::ostringstream what;
  what << "is too large: " << value << " " << unit << " is above " << limit << " " << unit << " (" << why << "): " << advice;
  fail(key, what.str());
}

// Limits that follow from the physics or the machine (README "Bad input"): bone cement sets within
// minutes, so an injection taking longer than a day is a typo (and a run over that many simulated seconds
// would not end); a snapshot count above 10000 fills the disk and the folder (a hostile 1e-300 s interval
// wrote 233k files). The SPH model's artificial sound speed is 1 m/s in the paper: one above water's
// 1500 m/s makes the time step (h / c) uselessly small; a drag coefficient (calibrated near 1) beyond
// 1e-6..1e6 is a typo.
constexpr double kMaxInjectionS = 86400.0;
constexpr double kMaxSnapshots = 10000.0;
// PMMA cements are injected at 10-3000 Pa.s and set as a dough of 1e4-1e5 Pa.s (Krebs et al. 2005, Baroud et al.
// 2006): a viscosity above 1e7 Pa.s is a typo, and the run's dimensionless numbers would overflow long before 1e308.
constexpr double kMaxViscosityPaS = 1e7;
// Below water's 1e-3 Pa.s no liquid exists, let alone a cement (10 Pa.s and up): 1e-300 Pa.s left the SPH
// time step unbounded ("no finite time step"), an error that named no key.
constexpr double kMinViscosityPaS = 1e-4;
// Less than a cubic millimetre is below one voxel of any CT the program reads: no spreading to predict.
constexpr double kMinVolumeMl = 1e-3;
// Upper ends: a vertebral body holds about 30-50 ml and a kit's syringes 10-20 ml, so a litre is past any
// injection; 1000 ml/s empties a 10 ml syringe in 10 ms. Beyond them a value is a typo or a unit slip, and an
// unchecked 1e308 went on to blame another key ("volume_ml 1e308": "flow_rate_ml_per_s is too small").
constexpr double kMaxVolumeMl = 1e3;
constexpr double kMaxFlowRateMlPerS = 1e3;
constexpr double kMinSoundSpeed = 1e-3, kMaxSoundSpeed = 1500.0;
constexpr double kMinDrag = 1e-6, kMaxDrag = 1e6;

double number(const json& v, const std::string& key) {
  if (!v.is_number()) fail(key, "must be a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(key, "must be finite");
  return x;
}

Eigen::Vector3d vector3(const json& v, const std::string& key) {
  if (!v.is_array() || v.size() != 3) fail(key, "must be an array of 3 numbers [x, y, z]");
  return {number(v[0], key), number(v[1], key), number(v[2], key)};
}

// Every text key is a short name (a preset, a law, a cement): a longer value is not one, and refusing it
// here keeps it out of the messages that echo it.
const std::string& shortName(const std::string& value, const std::string& key) {
  if (value.size() > 200) fail(key, "must be a short name (got " + std::to_string(value.size()) + " characters)");
  return value;
}

std::string text(const json& v, const std::string& key) {
  if (!v.is_string()) fail(key, "must be a string");
  return shortName(v.get_ref<const std::string&>(), key);
}

void setModelPreset(SceneConfig& s, const std::string& name) {
  s.modelPreset = shortName(name, "preset");
  try {
    (void)sph::modelPreset(s.modelPreset);
  } catch (const std::invalid_argument&) {
    fail("preset", "must be \"default\" or \"paper\" (got \"" + shown(s.modelPreset) + "\")");
  }
}

double finite(double x, const std::string& key) {
  if (!std::isfinite(x)) fail(key, "must be finite");
  return x;
}

Eigen::Vector3d finite(const std::array<double, 3>& v, const std::string& key) {
  return {finite(v[0], key), finite(v[1], key), finite(v[2], key)};
}

// Each setting the command gave, in the order applied, as (scene key, how the user gave it): "override key=value"
// for --set and for a typed field without an option, "--option value" for one given by an option (optionOfKey).
std::vector<std::pair<std::string, std::string>> givenSettings(const SceneSettings& g) {
  std::vector<std::pair<std::string, std::string>> given;
  for (const std::string& o : g.set) given.emplace_back(o.substr(0, o.find('=')), "override " + shown(o));
  auto add = [&](const std::string& key, const std::string& value) {
    const auto option = g.optionOfKey.find(key);
    if (option == g.optionOfKey.end()) {
      given.emplace_back(key, "override " + shown(key + "=" + value));
      return;
    }
    // As typed: a vector is x,y,z, a text bare.
    std::string typed = value;
    if (typed.size() >= 2 && (typed.front() == '[' || typed.front() == '"')) typed = typed.substr(1, typed.size() - 2);
    given.emplace_back(key, option->second + " " + shown(typed));
  };
  auto vector = [](const std::array<double, 3>& v) {
    return "[" + exactNumber(v[0]) + "," + exactNumber(v[1]) + "," + exactNumber(v[2]) + "]";
  };
  if (g.tipMm) add("tip_mm", vector(*g.tipMm));
  if (g.direction) add("direction", vector(*g.direction));
  if (g.volumeMl) add("volume_ml", exactNumber(*g.volumeMl));
  if (g.flowRateMlPerS) add("flow_rate_ml_per_s", exactNumber(*g.flowRateMlPerS));
  if (g.viscosityPaS) add("viscosity_pa_s", exactNumber(*g.viscosityPaS));
  if (g.snapshotIntervalS) add("snapshot_interval_s", exactNumber(*g.snapshotIntervalS));
  if (g.simulatedCtSnapshots) add("simulated_ct_snapshots", *g.simulatedCtSnapshots ? "true" : "false");
  if (g.modelPreset) add("preset", "\"" + *g.modelPreset + "\"");
  return given;
}

void requirePositive(double x, const std::string& key) {
  if (!(x > 0)) {
    std::ostringstream s;
    s << "must be > 0 (got " << x << ")";
    fail(key, s.str());
  }
}

} // namespace

const std::set<std::string>& sceneKeyNames() {
  // The same names as applySceneJson's branches (SceneConfigTest checks that each is accepted as a key).
  static const std::set<std::string> names{
      "scene_preset", "preset", "particle_radius_mm", "tip_mm", "direction", "cannula_inner_diameter_mm",
      "cannula_length_mm", "cannula_wall", "flow_rate_ml_per_s", "volume_ml", "viscosity_pa_s",
      "viscosity_rate_pa_per_s", "viscosity_table", "threshold_hu", "roi_size_mm", "snapshot_interval_s",
      "snapshot_arrays", "simulated_ct_snapshots", "solid_mass_factor", "drag_coefficient", "sound_speed_m_per_s", "integrator",
      "fixed_particle_sums", "fixed_field_spacing_over_h", "max_displacement_over_h", "neighbour_skin_over_h",
      "pressure_model", "pore_permeability_m2", "capillary_tension_n_per_m", "viscosity_law", "consistency_pa_s_n",
      "flow_index", "zero_shear_viscosity_pa_s", "infinite_shear_viscosity_pa_s", "carreau_time_constant_s",
      "viscosity_min_pa_s", "viscosity_max_pa_s", "mixing_to_injection_s", "curing_table", "cement",
      "curing_model", "curing_time_s", "cured_viscosity_pa_s", "curing_reference_time_s", "bone_model",
      "marrow_hu", "bone_tissue_hu", "kozeny_carman_diameter_mm", "cortical_hu", "soft_tissue_max_hu",
      "soft_tissue_permeability_m2", "stop_at_first_leak", "allow_tip_outside_bone", "labels_path",
      "label_table", "second_tip_withdrawal_mm", "second_tip_volume_ml", "cannula_gauge",
      "contact_angle_deg"};
  return names;
}

SceneConfig scenePreset(const std::string& name) {
  if (name != "paper")
    throw std::invalid_argument("scene: key 'scene_preset' must be \"paper\" (got \"" + shown(name) + "\")");
  return SceneConfig{}; // the struct's defaults are the paper's values
}

void applySceneJson(SceneConfig& s, const json& j) {
  if (!j.is_object()) throw std::invalid_argument("scene: the scene must be a JSON object");
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    const json& v = it.value();
    if (v.is_null()) fail(key, "has no value");
    if (key == "scene_preset") {
      const SceneConfig p = scenePreset(text(v, key));
      (void)p; // the preset is applied by the loaders before the other keys
    } else if (key == "preset") {
      setModelPreset(s, text(v, key));
    } else if (key == "particle_radius_mm") s.particleRadiusMm = number(v, key);
    else if (key == "tip_mm") s.tipMm = vector3(v, key);
    else if (key == "direction") s.direction = vector3(v, key);
    else if (key == "cannula_inner_diameter_mm") s.cannulaInnerDiameterMm = number(v, key);
    else if (key == "cannula_length_mm") s.cannulaLengthMm = number(v, key);
    else if (key == "cannula_wall") {
      if (!v.is_boolean()) fail(key, "must be true or false");
      s.cannulaWall = v.get<bool>();
    } else if (key == "flow_rate_ml_per_s") s.flowRateMlPerS = number(v, key);
    else if (key == "volume_ml") s.volumeMl = number(v, key);
    else if (key == "viscosity_pa_s") {
      s.viscosityPaS = number(v, key);
      s.viscosityTable.clear();
    } else if (key == "viscosity_rate_pa_per_s") {
      s.viscosityRatePaPerS = number(v, key);
      s.viscosityTable.clear();
    } else if (key == "viscosity_table") {
      if (!v.is_array() || v.empty()) fail(key, "must be a non-empty array of [t_s, mu_pa_s] pairs");
      std::vector<std::pair<double, double>> table;
      for (const json& row : v) {
        if (!row.is_array() || row.size() != 2) fail(key, "must be a non-empty array of [t_s, mu_pa_s] pairs");
        table.emplace_back(number(row[0], key), number(row[1], key));
      }
      s.viscosityTable = std::move(table);
      s.viscosityRatePaPerS.reset();
    } else if (key == "threshold_hu") s.thresholdHu = number(v, key);
    else if (key == "roi_size_mm") s.roiSizeMm = number(v, key);
    else if (key == "snapshot_interval_s") s.snapshotIntervalS = number(v, key);
    else if (key == "snapshot_arrays") {
      s.snapshotArrays = text(v, key);
      if (s.snapshotArrays != "growth" && s.snapshotArrays != "flow")
        fail(key, "must be \"growth\" (where the cement is, with its arrival times) or \"flow\" (every snapshot "
                  "also holds the pressure, volume and velocity of every voxel) (got \"" + shown(s.snapshotArrays) + "\")");
    }
    else if (key == "simulated_ct_snapshots") {
      if (!v.is_boolean()) fail(key, "must be true or false");
      s.simulatedCtSnapshots = v.get<bool>();
    }
    else if (key == "solid_mass_factor") s.solidMassFactor = number(v, key);
    else if (key == "drag_coefficient") s.dragCoefficient = number(v, key);
    else if (key == "sound_speed_m_per_s") s.soundSpeedMPerS = number(v, key);
    else if (key == "integrator") {
      s.integrator = text(v, key);
      try {
        (void)sph::parseIntegrator(*s.integrator);
      } catch (const std::exception& e) {
        fail(key, std::string("is not an integrator: ") + e.what());
      }
    } else if (key == "fixed_particle_sums") {
      s.fixedParticleSums = text(v, key);
      try {
        (void)sph::parseFixedSumMethod(*s.fixedParticleSums);
      } catch (const std::exception& e) {
        fail(key, std::string("is not a method: ") + e.what());
      }
    } else if (key == "fixed_field_spacing_over_h") s.fixedFieldSpacingOverH = number(v, key);
    else if (key == "max_displacement_over_h") s.maxDisplacementOverH = number(v, key);
    else if (key == "neighbour_skin_over_h") s.neighbourSkinOverH = number(v, key);
    else if (key == "pressure_model") {
      // "auto" or a registered injection model's name; which names this build has is the driver's to say
      // (InjectionModel.h: a model registered by a plug-in is a valid name too), here only its form.
      s.pressureModel = text(v, key);
      const bool nameLike = !s.pressureModel.empty() && s.pressureModel.size() <= 40 &&
                            s.pressureModel.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-") == std::string::npos;
      if (!nameLike)
        fail(key, "must be \"auto\" or an injection model's name, e.g. \"voxel-darcy\", \"incompressible\", "
                  "\"equation-of-state\" (got \"" + shown(s.pressureModel) + "\")");
    } else if (key == "pore_permeability_m2") {
      s.porePermeabilityM2 = number(v, key);
    } else if (key == "capillary_tension_n_per_m") {
      s.capillaryTensionNPerM = number(v, key);
    } else if (key == "contact_angle_deg") {
      s.contactAngleDeg = number(v, key);
    } else if (key == "viscosity_law") {
      s.viscosityLaw = text(v, key);
      if (s.viscosityLaw != "newtonian" && s.viscosityLaw != "power-law" && s.viscosityLaw != "carreau")
        fail(key, "must be \"newtonian\", \"power-law\" or \"carreau\" (got \"" + shown(s.viscosityLaw) + "\")");
    } else if (key == "consistency_pa_s_n") s.rheology.consistencyPaSn = number(v, key);
    else if (key == "flow_index") s.rheology.flowIndex = number(v, key);
    else if (key == "zero_shear_viscosity_pa_s") s.rheology.zeroShearViscosityPaS = number(v, key);
    else if (key == "infinite_shear_viscosity_pa_s") s.rheology.infiniteShearViscosityPaS = number(v, key);
    else if (key == "carreau_time_constant_s") s.rheology.timeConstantS = number(v, key);
    else if (key == "viscosity_min_pa_s") s.rheology.minimumViscosityPaS = number(v, key);
    else if (key == "viscosity_max_pa_s") s.rheology.maximumViscosityPaS = number(v, key);
    else if (key == "mixing_to_injection_s") s.mixingToInjectionS = number(v, key);
    else if (key == "curing_table") {
      if (!v.is_array() || v.empty()) fail(key, "must be a non-empty array of [t_since_mixing_s, factor] pairs");
      s.curingTable.clear();
      for (const json& row : v) {
        if (!row.is_array() || row.size() != 2) fail(key, "must be a non-empty array of [t_since_mixing_s, factor] pairs");
        s.curingTable.emplace_back(number(row[0], key), number(row[1], key));
      }
    } else if (key == "cement") {
      s.cement = text(v, key);
      try {
        (void)sph::bundledCement(*s.cement);
      } catch (const std::invalid_argument& e) {
        fail(key, e.what());
      }
    } else if (key == "curing_model") {
      s.curingModel = text(v, key);
      if (*s.curingModel != "none" && *s.curingModel != "table" && *s.curingModel != "exponential")
        fail(key, "must be \"none\", \"table\" or \"exponential\" (got \"" + shown(*s.curingModel) + "\")");
    } else if (key == "curing_time_s") s.curingTimeS = number(v, key);
    else if (key == "cured_viscosity_pa_s") s.curedViscosityPaS = number(v, key);
    else if (key == "curing_reference_time_s") s.curingReferenceTimeS = number(v, key);
    else if (key == "bone_model") {
      s.boneModel = text(v, key);
      if (s.boneModel != "auto" && s.boneModel != "pore-resolved" && s.boneModel != "continuum")
        fail(key, "must be \"auto\", \"pore-resolved\" or \"continuum\" (got \"" + shown(s.boneModel) + "\")");
    } else if (key == "marrow_hu") s.bone.marrowHu = number(v, key);
    else if (key == "bone_tissue_hu") s.bone.boneTissueHu = number(v, key);
    else if (key == "kozeny_carman_diameter_mm") s.bone.kozenyCarmanDiameterMm = number(v, key);
    else if (key == "cortical_hu") s.bone.corticalHu = number(v, key);
    else if (key == "soft_tissue_max_hu") s.bone.softTissueMaxHu = number(v, key);
    else if (key == "soft_tissue_permeability_m2") s.bone.softTissuePermeabilityM2 = number(v, key);
    else if (key == "stop_at_first_leak") {
      if (!v.is_boolean()) fail(key, "must be true or false");
      s.stopAtFirstLeak = v.get<bool>();
    } else if (key == "allow_tip_outside_bone") {
      if (!v.is_boolean()) fail(key, "must be true or false");
      s.allowTipOutsideBone = v.get<bool>();
    } else if (key == "labels_path") {
      if (!v.is_string() || v.get_ref<const std::string&>().empty() || v.get_ref<const std::string&>().size() > 4096)
        fail(key, "must be the path of a label map (a non-empty string)");
      s.labelsPath = v.get<std::string>();
    } else if (key == "label_table") {
      if (!v.is_object()) fail(key, "must be an object of class -> [labels] (README, \"Your own CT\")");
      s.labelTable = v;
    } else if (key == "second_tip_withdrawal_mm") s.secondTipWithdrawalMm = number(v, key);
    else if (key == "second_tip_volume_ml") s.secondTipVolumeMl = number(v, key);
    else if (key == "cannula_gauge") {
      const std::string name = text(v, key);
      try {
        s.cannulaInnerDiameterMm = sph::cannulaInnerDiameterMm(name);
        s.cannulaGauge = sph::canonicalCannulaGauge(name);
      } catch (const std::invalid_argument& e) {
        fail(key, e.what());
      }
    } else
      throw std::invalid_argument("scene: unknown key '" + shown(key) + "'");
    s.explicitKeys.insert(key);
  }
}

void applySceneOverride(SceneConfig& s, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw std::invalid_argument("--set '" + shown(assignment) + "': an override must be key=value (a scene key, '=', "
                                "then a JSON value)");
  const std::string key = assignment.substr(0, eq), value = assignment.substr(eq + 1);
  if (value.empty()) fail(key, "has no value");
  json v = json::parse(value, nullptr, /*allow_exceptions=*/false);
  if (v.is_discarded()) v = value; // a bare word: a string
  applySceneJson(s, json{{key, v}});
}

void applySceneSettings(SceneConfig& s, const SceneSettings& g) {
  for (const std::string& o : g.set) applySceneOverride(s, o);
  // A number the key would refuse in a scene file is refused here as there, naming the key.
  auto put = [&](auto& field, const auto& given, const char* key) {
    if (!given) return false;
    field = finite(*given, key);
    s.explicitKeys.insert(key);
    return true;
  };
  put(s.tipMm, g.tipMm, "tip_mm");
  put(s.direction, g.direction, "direction");
  put(s.volumeMl, g.volumeMl, "volume_ml");
  put(s.flowRateMlPerS, g.flowRateMlPerS, "flow_rate_ml_per_s");
  if (put(s.viscosityPaS, g.viscosityPaS, "viscosity_pa_s")) s.viscosityTable.clear(); // a constant, as the key
  put(s.snapshotIntervalS, g.snapshotIntervalS, "snapshot_interval_s");
  if (g.simulatedCtSnapshots) {
    s.simulatedCtSnapshots = *g.simulatedCtSnapshots;
    s.explicitKeys.insert("simulated_ct_snapshots");
  }
  if (g.modelPreset) {
    setModelPreset(s, *g.modelPreset);
    s.explicitKeys.insert("preset");
  }
}

sph::ViscositySchedule SceneConfig::viscositySchedule() const {
  if (!viscosityTable.empty()) return sph::ViscositySchedule::table(viscosityTable);
  if (viscosityRatePaPerS) return sph::ViscositySchedule::linear(viscosityPaS, *viscosityRatePaPerS);
  return sph::ViscositySchedule::constant(viscosityPaS);
}

void SceneConfig::validate() const {
  if (!tipMm) throw std::invalid_argument("scene: key 'tip_mm' is missing (the cannula tip [x, y, z] in mm)");
  requirePositive(particleRadiusMm, "particle_radius_mm");
  if (direction.norm() == 0) fail("direction", "must not be zero");
  requirePositive(cannulaInnerDiameterMm, "cannula_inner_diameter_mm");
  if (cannulaInnerDiameterMm < spacingM() * 1e3)
    fail("cannula_inner_diameter_mm", "must be at least one particle diameter (2 particle_radius_mm)");
  requirePositive(cannulaLengthMm, "cannula_length_mm");
  requirePositive(flowRateMlPerS, "flow_rate_ml_per_s");
  requirePositive(volumeMl, "volume_ml");
  requireAtLeast(volumeMl, kMinVolumeMl, "volume_ml", "ml", "one cubic millimetre, below a CT voxel", "give the volume in ml");
  requireAtMost(volumeMl, kMaxVolumeMl, "volume_ml", "ml", "a vertebral body holds 30-50 ml", "give the volume in ml");
  requireAtMost(flowRateMlPerS, kMaxFlowRateMlPerS, "flow_rate_ml_per_s", "ml/s", "clinical rates are 0.01-0.5 ml/s",
                "give the rate in ml/s");
  if (!(injectionDurationS() <= kMaxInjectionS)) {
    std::ostringstream what;
    what << "is too small: " << flowRateMlPerS << " ml/s takes " << injectionDurationS() << " s for volume_ml "
         << volumeMl << ", longer than a day (86400 s; cement sets in minutes): use at least " << volumeMl / kMaxInjectionS
         << " ml/s";
    fail("flow_rate_ml_per_s", what.str());
  }
  requirePositive(viscosityPaS, "viscosity_pa_s");
  requireAtLeast(viscosityPaS, kMinViscosityPaS, "viscosity_pa_s", "Pa.s",
                 "thinner than water, 1e-3 Pa.s; cements are 10 Pa.s and up", "give the viscosity in Pa.s");
  requireAtMost(viscosityPaS, kMaxViscosityPaS, "viscosity_pa_s", "Pa.s", "a setting PMMA dough is 1e4-1e5 Pa.s",
                "give the viscosity in Pa.s");
  if (viscosityRatePaPerS) requirePositive(*viscosityRatePaPerS, "viscosity_rate_pa_per_s");
  if (!viscosityTable.empty()) {
    for (std::size_t k = 0; k < viscosityTable.size(); ++k) {
      if (!(viscosityTable[k].second > 0 && viscosityTable[k].second <= kMaxViscosityPaS))
        fail("viscosity_table", "viscosities must be > 0 and at most 1e7 Pa.s");
      if (k > 0 && !(viscosityTable[k].first > viscosityTable[k - 1].first))
        fail("viscosity_table", "times must increase strictly");
    }
  }
  requirePositive(roiSizeMm, "roi_size_mm");
  if (roiSizeMm < 4 * spacingM() * 1e3) fail("roi_size_mm", "must be at least 4 particle diameters");
  requirePositive(snapshotIntervalS, "snapshot_interval_s");
  if (!(injectionDurationS() / snapshotIntervalS <= kMaxSnapshots)) {
    std::ostringstream what;
    what << "is too small: " << snapshotIntervalS << " s over a " << injectionDurationS()
         << " s injection (volume_ml / flow_rate_ml_per_s) is more than " << kMaxSnapshots
         << " snapshots: use at least " << injectionDurationS() / kMaxSnapshots << " s";
    fail("snapshot_interval_s", what.str());
  }
  requirePositive(solidMassFactor, "solid_mass_factor");
  // Trabecular bone 2.7e-11 .. 2e-8 m^2 (model-notes); outside 1e-18 .. 1e-3 m^2 a value is a typo.
  if (porePermeabilityM2 && !(*porePermeabilityM2 >= 1e-18 && *porePermeabilityM2 <= 1e-3))
    fail("pore_permeability_m2", "must be between 1e-18 and 1e-3 m^2");
  try {
    (void)sph::makeRheology(viscosityLaw, rheology);
  } catch (const std::invalid_argument& e) {
    fail("viscosity_law", e.what());
  }
  if (const char* problem = bone.problem()) fail("bone_model", problem);
  if (!(mixingToInjectionS >= 0) || !std::isfinite(mixingToInjectionS)) fail("mixing_to_injection_s", "must be >= 0 s");
  (void)curing(); // the curing keys, each error naming its key
  if (!(capillaryTensionNPerM >= 0) || !std::isfinite(capillaryTensionNPerM) || capillaryTensionNPerM > 1.0)
    fail("capillary_tension_n_per_m", "must be in [0, 1] N/m (0: no capillary entry)");
  // Measured through the displaced fluid (marrow): below 90 degrees the cement is the non-wetting phase and must be
  // pushed into a throat; at or above 90 it would be drawn in (imbibition), which the entry model does not describe.
  if (!(contactAngleDeg >= 0 && contactAngleDeg < 90) || !std::isfinite(contactAngleDeg))
    fail("contact_angle_deg", "must be in [0, 90) degrees (measured through the marrow; 0: the largest entry "
                              "pressure; 90 or more would make the cement the wetting phase, not modelled)");
  auto requireWithin = [](const std::optional<double>& x, double lo, double hi, const char* key, const char* unit) {
    if (x && !(*x >= lo && *x <= hi)) {
      std::ostringstream what;
      what << "must be " << lo << ".." << hi << unit << " (got " << *x << ")";
      fail(key, what.str());
    }
  };
  requireWithin(dragCoefficient, kMinDrag, kMaxDrag, "drag_coefficient", "");
  requireWithin(soundSpeedMPerS, kMinSoundSpeed, kMaxSoundSpeed, "sound_speed_m_per_s", " m/s");
  auto requireFraction = [](const std::optional<double>& x, double upper, const char* key) {
    if (x && !(*x > 0 && *x <= upper)) fail(key, "must be > 0 and <= " + std::to_string(upper).substr(0, 3));
  };
  requireFraction(fixedFieldSpacingOverH, 1.0, "fixed_field_spacing_over_h");
  requireFraction(maxDisplacementOverH, 1.0, "max_displacement_over_h");
  requireFraction(neighbourSkinOverH, 2.0, "neighbour_skin_over_h");
  if (secondTipWithdrawalMm) {
    if (!(*secondTipWithdrawalMm > 0 && *secondTipWithdrawalMm < 1000))
      fail("second_tip_withdrawal_mm", "must be > 0 and < 1000 mm");
    if (!(secondTipVolumeMl > 0 && secondTipVolumeMl < volumeMl))
      fail("second_tip_volume_ml", "must be > 0 and less than volume_ml (the first tip takes the rest)");
  } else if (secondTipVolumeMl != 0) {
    fail("second_tip_volume_ml", "needs second_tip_withdrawal_mm (how far back the second tip lies)");
  }
}

sph::FixedSumMethod SceneConfig::fixedSumMethod() const {
  if (fixedParticleSums) return sph::parseFixedSumMethod(*fixedParticleSums);
  // The paper's preset sums pair by pair as the paper; the default tabulates (VALIDATION.md: its cost).
  return modelPreset == "paper" ? sph::FixedSumMethod::Exact : sph::FixedSumMethod::Tabulated;
}

SceneConfig sceneFromJson(const json& j, const SceneSettings& settings) {
  if (!j.is_object()) throw std::invalid_argument("scene: the scene must be a JSON object");
  SceneConfig s = scenePreset("paper");
  if (j.contains("scene_preset")) {
    if (j["scene_preset"].is_null()) fail("scene_preset", "has no value");
    s = scenePreset(text(j["scene_preset"], "scene_preset"));
  }
  applySceneJson(s, j);
  applySceneSettings(s, settings);
  s.validate();
  return s;
}

SceneConfig sceneFromJson(const json& j, const std::vector<std::string>& overrides) {
  SceneSettings settings;
  settings.set = overrides;
  return sceneFromJson(j, settings);
}

namespace {

// Where a scene file stops being JSON, for the one line that refuses it: the line and column, the key whose value
// (or name) it is in, and the parser's reason without its "[json.exception...]" tag ("line 3, column 21, in key
// 'viscosity_pa_s': invalid literal"). A tracking-only SAX pass over the text: nothing is built.
class JsonErrorLocator : public nlohmann::json_sax<json> {
public:
  explicit JsonErrorLocator(const std::string& text) : text_(text) {}
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return keys_.emplace_back(), true; }
  bool key(string_t& k) override {
    if (!keys_.empty()) keys_.back() = k;
    return true;
  }
  bool end_object() override {
    if (!keys_.empty()) keys_.pop_back();
    return true;
  }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& e) override {
    std::string reason = e.what();
    if (const auto tag = reason.find("] "); reason.rfind("[json.exception", 0) == 0 && tag != std::string::npos)
      reason.erase(0, tag + 2);
    if (const auto at = reason.find(": "); reason.rfind("parse error", 0) == 0 && at != std::string::npos)
      reason.erase(0, at + 2); // "parse error at line 1, column 5: " is ours to say
    if (const auto more = reason.find("; "); more != std::string::npos) reason.erase(more); // "; last read: ..."
    if (const auto dash = reason.find(" - "); dash != std::string::npos) reason.erase(0, dash + 3);
    what_ = where(std::min(position, text_.size())) + ": " + shown(reason);
    return false;
  }
  // "line L, column C[, in key 'K']" for a byte offset into the text.
  std::string where(std::size_t offset) const {
    const std::size_t line = 1 + std::size_t(std::count(text_.begin(), text_.begin() + std::ptrdiff_t(offset), '\n'));
    const std::size_t lineStart = offset == 0 ? 0 : text_.rfind('\n', offset - 1);
    const std::size_t column = lineStart == std::string::npos || offset == 0 ? offset + 1 : offset - lineStart;
    std::string at = "line " + std::to_string(line) + ", column " + std::to_string(column);
    for (auto k = keys_.rbegin(); k != keys_.rend(); ++k)
      if (!k->empty()) return at + ", in key '" + shown(*k) + "'";
    return at;
  }
  const std::string& what() const { return what_; }

private:
  const std::string& text_;
  std::vector<std::string> keys_;
  std::string what_;
};

// The refusal of a scene text that is not one JSON object: where and why.
std::string jsonProblem(const std::string& text) {
  JsonErrorLocator locator(text);
  (void)json::sax_parse(text, &locator);
  return locator.what().empty() ? "not valid JSON" : locator.what();
}

// Where the byte at `offset` lies: the SAX pass over the text before it, which ends inside the innermost key.
std::string jsonPlace(const std::string& text, std::size_t offset) {
  const std::string before = text.substr(0, offset);
  JsonErrorLocator locator(before);
  (void)json::sax_parse(before, &locator);
  return locator.where(offset);
}

} // namespace

SceneConfig loadSceneFile(const std::string& path, const SceneSettings& settings) {
  // Only a regular file is opened: opening a FIFO with no writer blocks forever (`--scene fifo.json` hung), a
  // folder opens and reads as nothing, and a device never ends.
  {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw std::invalid_argument(path + ": no such scene file");
    if (!std::filesystem::is_regular_file(path, ec))
      throw std::invalid_argument(path + ": not a regular file (a folder, pipe or device); give the scene's JSON file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot open the scene file");
  // The whole file is the JSON object: read it all (a scene is a few kB; 16 MiB is far past any), and refuse
  // a NUL byte, which the stream parser takes for the end of input, accepting the garbage after it.
  constexpr std::size_t kMaxSceneBytes = std::size_t(16) << 20;
  std::string text(kMaxSceneBytes + 1, '\0');
  in.read(text.data(), std::streamsize(text.size()));
  text.resize(std::size_t(in.gcount()));
  if (text.size() > kMaxSceneBytes)
    throw std::invalid_argument(path + ": the scene file is over 16 MiB; a scene is a JSON object of a few kB");
  if (const auto nul = text.find('\0'); nul != std::string::npos)
    throw std::invalid_argument(path + ": " + jsonPlace(text, nul) + " (byte " + std::to_string(nul) +
                                "): a NUL byte, not a text JSON file (damaged, or something appended to it)");
  // A key given twice in one object is refused: the parser keeps the last silently, so which of two
  // volumes was injected depended on their order (the corpus of issue 21 found it accepted).
  std::vector<std::set<std::string>> keysOfOpenObjects;
  std::string duplicateKey;
  const json::parser_callback_t noteDuplicates = [&](int, json::parse_event_t event, json& parsed) {
    if (event == json::parse_event_t::object_start) keysOfOpenObjects.emplace_back();
    else if (event == json::parse_event_t::object_end && !keysOfOpenObjects.empty()) keysOfOpenObjects.pop_back();
    else if (event == json::parse_event_t::key && !keysOfOpenObjects.empty() && duplicateKey.empty() &&
             !keysOfOpenObjects.back().insert(parsed.get<std::string>()).second)
      duplicateKey = parsed.get<std::string>();
    return true;
  };
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw std::invalid_argument(path + ": the scene file is empty: a scene is one JSON object, such as "
                                       "{\"tip_mm\": [x, y, z], \"volume_ml\": 1}");
  json j = json::parse(text, noteDuplicates, /*allow_exceptions=*/false);
  if (j.is_discarded())
    throw std::invalid_argument(path + ": " + jsonProblem(text) +
                                ": not valid JSON (a scene is one object, nothing after it); mend the file there");
  if (!duplicateKey.empty())
    throw std::invalid_argument(path + ": key '" + duplicateKey.substr(0, 40) +
                                "' appears twice in one object: keep the one you mean and remove the other");
  try {
    return sceneFromJson(j, settings);
  } catch (const std::invalid_argument& e) {
    // Blame the command line's setting when it set the key at fault, else the file.
    const std::string what = e.what();
    if (what.rfind("--set '", 0) == 0) throw; // a malformed --set names itself
    for (const auto& [key, given] : givenSettings(settings))
      if (what.find("'" + key + "'") != std::string::npos)
        throw std::invalid_argument(given + " (command line): " + what);
    throw std::invalid_argument(path + ": " + what);
  }
}

SceneConfig loadSceneFile(const std::string& path, const std::vector<std::string>& overrides) {
  SceneSettings settings;
  settings.set = overrides;
  return loadSceneFile(path, settings);
}

double SceneConfig::referenceViscosityPaS() const {
  if (viscosityLaw == "power-law") return rheology.consistencyPaSn;
  if (viscosityLaw == "carreau") return rheology.zeroShearViscosityPaS;
  return viscosityPaS;
}

sph::CuringCurve SceneConfig::curing() const {
  const std::string kind = curingModel ? *curingModel : cement ? "exponential" : !curingTable.empty() ? "table" : "none";
  if (kind == "none") {
    if (!curingTable.empty()) fail("curing_table", "is not used with curing_model \"none\": remove one of them");
    return sph::CuringCurve::none();
  }
  if (kind == "table") {
    if (curingTable.empty()) fail("curing_model", "\"table\" needs curing_table [[t_since_mixing_s, factor], ...]");
    try {
      return sph::CuringCurve::table(curingTable);
    } catch (const std::invalid_argument& e) {
      fail("curing_table", std::string(e.what()).substr(std::string("curing table: ").size()));
    }
  }
  if (!curingTable.empty())
    fail("curing_table", "is not used with curing_model \"exponential\" (or a cement): remove one of them");
  if (viscosityRatePaPerS || !viscosityTable.empty())
    fail(viscosityRatePaPerS ? "viscosity_rate_pa_per_s" : "viscosity_table",
         "is a second viscosity rise besides the curing curve (curing_model \"exponential\" or cement): remove one");
  std::optional<sph::BundledCement> bundled;
  if (cement) bundled = sph::bundledCement(*cement);
  const std::optional<double> tCure = curingTimeS ? curingTimeS : bundled ? std::optional<double>(bundled->curingTimeS) : std::nullopt;
  const std::optional<double> muCured =
      curedViscosityPaS ? curedViscosityPaS : bundled ? std::optional<double>(bundled->curedViscosityPaS) : std::nullopt;
  if (!tCure) fail("curing_time_s", "is missing: curing_model \"exponential\" needs it (or a bundled cement)");
  if (!muCured) fail("cured_viscosity_pa_s", "is missing: curing_model \"exponential\" needs it (or a bundled cement)");
  if (!(curingReferenceTimeS >= 0)) fail("curing_reference_time_s", "must be >= 0 s (time since mixing)");
  if (!(*tCure > curingReferenceTimeS)) fail("curing_time_s", "must come after curing_reference_time_s (both since mixing)");
  if (!(*muCured > referenceViscosityPaS())) {
    std::ostringstream what;
    what << "must exceed the law's viscosity at curing_reference_time_s (" << referenceViscosityPaS() << " Pa s)";
    fail("cured_viscosity_pa_s", what.str());
  }
  return sph::CuringCurve::exponential(curingReferenceTimeS, referenceViscosityPaS(), *tCure, *muCured);
}

double SceneConfig::curingFactor(double t) const { return curing().factor(mixingToInjectionS + t); }

json toJson(const SceneConfig& s) {
  json j;
  j["scene_preset"] = s.scenePreset;
  j["preset"] = s.modelPreset;
  j["particle_radius_mm"] = s.particleRadiusMm;
  if (s.tipMm) j["tip_mm"] = {s.tipMm->x(), s.tipMm->y(), s.tipMm->z()};
  j["direction"] = {s.direction.x(), s.direction.y(), s.direction.z()};
  j["cannula_inner_diameter_mm"] = s.cannulaInnerDiameterMm;
  j["cannula_length_mm"] = s.cannulaLengthMm;
  j["cannula_wall"] = s.cannulaWall;
  j["flow_rate_ml_per_s"] = s.flowRateMlPerS;
  j["volume_ml"] = s.volumeMl;
  if (s.viscosityTable.empty()) {
    j["viscosity_pa_s"] = s.viscosityPaS;
    if (s.viscosityRatePaPerS) j["viscosity_rate_pa_per_s"] = *s.viscosityRatePaPerS;
  } else {
    j["viscosity_table"] = json::array();
    for (const auto& [t, mu] : s.viscosityTable) j["viscosity_table"].push_back({t, mu});
  }
  j["threshold_hu"] = s.thresholdHu;
  j["roi_size_mm"] = s.roiSizeMm;
  j["snapshot_interval_s"] = s.snapshotIntervalS;
  j["snapshot_arrays"] = s.snapshotArrays;
  j["simulated_ct_snapshots"] = s.simulatedCtSnapshots;
  j["solid_mass_factor"] = s.solidMassFactor;
  if (s.dragCoefficient) j["drag_coefficient"] = *s.dragCoefficient;
  if (s.soundSpeedMPerS) j["sound_speed_m_per_s"] = *s.soundSpeedMPerS;
  if (s.integrator) j["integrator"] = *s.integrator;
  j["fixed_particle_sums"] = sph::toString(s.fixedSumMethod());
  if (s.fixedFieldSpacingOverH) j["fixed_field_spacing_over_h"] = *s.fixedFieldSpacingOverH;
  if (s.maxDisplacementOverH) j["max_displacement_over_h"] = *s.maxDisplacementOverH;
  if (s.neighbourSkinOverH) j["neighbour_skin_over_h"] = *s.neighbourSkinOverH;
  j["pressure_model"] = s.pressureModel;
  if (s.porePermeabilityM2) j["pore_permeability_m2"] = *s.porePermeabilityM2;
  j["capillary_tension_n_per_m"] = s.capillaryTensionNPerM;
  j["contact_angle_deg"] = s.contactAngleDeg;
  j["viscosity_law"] = s.viscosityLaw;
  if (s.viscosityLaw == "power-law") {
    j["consistency_pa_s_n"] = s.rheology.consistencyPaSn;
    j["flow_index"] = s.rheology.flowIndex;
  } else if (s.viscosityLaw == "carreau") {
    j["zero_shear_viscosity_pa_s"] = s.rheology.zeroShearViscosityPaS;
    j["infinite_shear_viscosity_pa_s"] = s.rheology.infiniteShearViscosityPaS;
    j["carreau_time_constant_s"] = s.rheology.timeConstantS;
    j["flow_index"] = s.rheology.flowIndex;
  }
  j["viscosity_min_pa_s"] = s.rheology.minimumViscosityPaS;
  j["viscosity_max_pa_s"] = s.rheology.maximumViscosityPaS;
  j["mixing_to_injection_s"] = s.mixingToInjectionS;
  if (!s.curingTable.empty()) {
    j["curing_table"] = json::array();
    for (const auto& [t, f] : s.curingTable) j["curing_table"].push_back({t, f});
  }
  if (s.cement) j["cement"] = *s.cement;
  if (s.curingModel) j["curing_model"] = *s.curingModel;
  if (s.curingTimeS) j["curing_time_s"] = *s.curingTimeS;
  if (s.curedViscosityPaS) j["cured_viscosity_pa_s"] = *s.curedViscosityPaS;
  if (s.curingReferenceTimeS != 0.0) j["curing_reference_time_s"] = s.curingReferenceTimeS; // 0: the default
  if (s.cannulaGauge) j["cannula_gauge"] = *s.cannulaGauge;
  j["bone_model"] = s.boneModel;
  j["marrow_hu"] = s.bone.marrowHu;
  j["bone_tissue_hu"] = s.bone.boneTissueHu;
  j["kozeny_carman_diameter_mm"] = s.bone.kozenyCarmanDiameterMm;
  j["cortical_hu"] = s.bone.corticalHu;
  j["soft_tissue_max_hu"] = s.bone.softTissueMaxHu;
  j["soft_tissue_permeability_m2"] = s.bone.softTissuePermeabilityM2;
  j["stop_at_first_leak"] = s.stopAtFirstLeak;
  if (s.allowTipOutsideBone) j["allow_tip_outside_bone"] = true; // only when set: recorded scenes stay as they were
  if (!s.labelsPath.empty()) j["labels_path"] = s.labelsPath;
  if (!s.labelTable.is_null()) j["label_table"] = s.labelTable;
  if (s.secondTipWithdrawalMm) {
    j["second_tip_withdrawal_mm"] = *s.secondTipWithdrawalMm;
    j["second_tip_volume_ml"] = s.secondTipVolumeMl;
  }
  return j;
}

// As the command line's overrides were written when they were "key=value" strings.
std::string exactNumber(double x) {
  std::ostringstream s;
  s.precision(17);
  s << x;
  return s.str();
}

} // namespace cementsph::scene
