#include "cementsph/scene/InjectionModel.h"

#include <stdexcept>

namespace cementsph::scene {

using nlohmann::json;

json InjectionSummary::toJson() const {
  json m;
  m["volume_requested_ml"] = volumeRequestedMl;
  m["volume_injected_ml"] = volumeInjectedMl;
  m["cement_volume_ml"] = cementVolumeMl;
  m["volume_history"] = volumeHistory;
  m["simulated_time_s"] = simulatedTimeS;
  m["wall_time_s"] = wallTimeS;
  m["real_time_factor"] = wallTimeS > 0 ? simulatedTimeS / wallTimeS : 0.0; // simulated seconds per wall second
  m["stopped_early"] = stoppedEarly;
  m["stopped_at_first_leak"] = stoppedAtFirstLeak;
  m["steps"] = steps;
  m["cement_points"] = cementPoints;
  if (particles) {
    m["fluid_particles"] = particles->fluid;
    m["fixed_particles"] = particles->fixed;
    m["cannula_wall_particles"] = particles->cannulaWall;
    m["escaped_particles"] = particles->escaped;
  }
  m["pressure_model"] = engine;
  m["model"] = model;
  m["model_reason"] = modelReason;
  m["recommended_pressure_model"] = recommendedPressureModel;
  m["model_preset"] = modelPreset;
  m["resistance"] = resistance;
  m["viscosity_law"] = viscosityLaw;
  m["bone_model"] = boneModel;
  m["bone_model_reason"] = boneModelReason;
  m["dimensionless_numbers"] = dimensionlessNumbers;
  m["pressure_is_physical"] = pressureIsPhysical;
  m["ct_resampled_to_axis_aligned"] = ctResampled;
  m["ct_orientation"] = ctOrientation;
  m["roi_start_index"] = roiStart; // on the axis-aligned CT's grid, relative to its region start
  m["roi_voxels"] = roiSize;
  m["solid_voxels_kept"] = solidVoxelsKept;
  m["solid_voxels_total"] = solidVoxelsTotal;
  m["connected_pore_voxels"] = connectedPoreVoxels;
  m["final_tip_pressure_pa"] = finalTipPressurePa;
  m["max_tip_pressure_pa"] = maxTipPressurePa;
  m["tip_pressure_baseline_pa"] = tipPressureBaselinePa;
  m["cannula_pressure_drop_pa"] = cannulaPressureDropPa;
  m["injection_pressure_pa"] = injectionPressurePa;
  m["max_injection_pressure_pa"] = maxInjectionPressurePa;
  m["mean_spreading_distance_mm"] = meanSpreadingDistanceMm;
  m["mass_balance_error"] = massBalanceError;
  m["fluid_in_solid_fraction"] = fluidInSolidFraction;
  m["final_viscosity_pa_s"] = finalViscosityPaS;
  m["simulated_ct_hu_per_relative_density"] = huPerRelativeDensity;
  m["leakage_assessed"] = leakageAssessed;
  m["leakage_volume_ml"] = leakageVolumeMl;
  json sites = json::array();
  for (const LeakageSite& l : leakageSites)
    sites.push_back({{"position_mm", l.positionMm}, {"first_time_s", l.firstTimeS}, {"volume_ml", l.volumeMl},
                     {"site_class", l.siteClass}});
  m["leakage_sites"] = sites;
  m["warnings"] = warnings;
  return m;
}

namespace {

template <typename T>
T field(const json& m, const char* key) {
  try {
    return m.at(key).get<T>();
  } catch (const json::exception&) {
    throw std::invalid_argument(std::string("injection summary: key \"") + key + "\" missing or of the wrong type");
  }
}

} // namespace

InjectionSummary InjectionSummary::fromJson(const json& m) {
  InjectionSummary s;
  s.volumeRequestedMl = field<double>(m, "volume_requested_ml");
  s.volumeInjectedMl = field<double>(m, "volume_injected_ml");
  s.cementVolumeMl = field<double>(m, "cement_volume_ml");
  s.volumeHistory = field<json>(m, "volume_history");
  s.simulatedTimeS = field<double>(m, "simulated_time_s");
  s.wallTimeS = field<double>(m, "wall_time_s");
  s.stoppedEarly = field<bool>(m, "stopped_early");
  s.stoppedAtFirstLeak = field<bool>(m, "stopped_at_first_leak");
  s.steps = field<std::size_t>(m, "steps");
  s.cementPoints = field<std::size_t>(m, "cement_points");
  if (m.contains("fluid_particles"))
    s.particles = ParticleCounts{field<std::size_t>(m, "fluid_particles"), field<std::size_t>(m, "fixed_particles"),
                                 field<std::size_t>(m, "cannula_wall_particles"),
                                 field<std::size_t>(m, "escaped_particles")};
  s.engine = field<std::string>(m, "pressure_model");
  s.model = field<std::string>(m, "model");
  s.modelReason = field<std::string>(m, "model_reason");
  s.recommendedPressureModel = field<std::string>(m, "recommended_pressure_model");
  s.modelPreset = field<std::string>(m, "model_preset");
  s.resistance = field<std::string>(m, "resistance");
  s.viscosityLaw = field<std::string>(m, "viscosity_law");
  s.boneModel = field<std::string>(m, "bone_model");
  s.boneModelReason = field<std::string>(m, "bone_model_reason");
  s.dimensionlessNumbers = field<json>(m, "dimensionless_numbers");
  s.pressureIsPhysical = field<bool>(m, "pressure_is_physical");
  s.ctResampled = field<bool>(m, "ct_resampled_to_axis_aligned");
  s.ctOrientation = field<std::string>(m, "ct_orientation");
  s.roiStart = field<std::array<long, 3>>(m, "roi_start_index");
  s.roiSize = field<std::array<long, 3>>(m, "roi_voxels");
  s.solidVoxelsKept = field<std::size_t>(m, "solid_voxels_kept");
  s.solidVoxelsTotal = field<std::size_t>(m, "solid_voxels_total");
  s.connectedPoreVoxels = field<std::size_t>(m, "connected_pore_voxels");
  s.finalTipPressurePa = field<double>(m, "final_tip_pressure_pa");
  s.maxTipPressurePa = field<double>(m, "max_tip_pressure_pa");
  s.tipPressureBaselinePa = field<double>(m, "tip_pressure_baseline_pa");
  s.cannulaPressureDropPa = field<double>(m, "cannula_pressure_drop_pa");
  s.injectionPressurePa = field<double>(m, "injection_pressure_pa");
  s.maxInjectionPressurePa = field<double>(m, "max_injection_pressure_pa");
  s.meanSpreadingDistanceMm = field<double>(m, "mean_spreading_distance_mm");
  s.massBalanceError = field<double>(m, "mass_balance_error");
  s.fluidInSolidFraction = field<double>(m, "fluid_in_solid_fraction");
  s.finalViscosityPaS = field<double>(m, "final_viscosity_pa_s");
  s.huPerRelativeDensity = field<double>(m, "simulated_ct_hu_per_relative_density");
  s.leakageAssessed = field<bool>(m, "leakage_assessed");
  s.leakageVolumeMl = field<double>(m, "leakage_volume_ml");
  s.warnings = field<std::vector<std::string>>(m, "warnings");
  for (const json& l : field<json>(m, "leakage_sites"))
    s.leakageSites.push_back({field<std::array<double, 3>>(l, "position_mm"), field<double>(l, "first_time_s"),
                              field<double>(l, "volume_ml"), field<std::string>(l, "site_class")});
  return s;
}

void addPressureSolverFigures(json& e, std::size_t solves, std::size_t iterations, double worstResidual,
                              std::size_t unconverged, double solveSeconds) {
  e["pressure_solves"] = solves;
  e["pressure_solver_iterations_mean"] = solves ? double(iterations) / double(solves) : 0.0;
  e["pressure_solver_worst_residual"] = worstResidual;
  e["pressure_solver_unconverged"] = unconverged;
  e["pressure_solve_wall_s"] = solveSeconds;
}

InjectionModelRegistry& InjectionModelRegistry::instance() {
  static InjectionModelRegistry registry = [] {
    InjectionModelRegistry r;
    registerBuiltInInjectionModels(r);
    return r;
  }();
  return registry;
}

void InjectionModelRegistry::add(const std::string& name, Factory factory, std::string description) {
  if (name.empty() || !factory) throw std::invalid_argument("injection model registry: a model needs a name and a factory");
  if (has(name)) throw std::invalid_argument("injection model registry: \"" + name + "\" is registered already");
  entries_[name] = Entry{std::move(factory), std::move(description), std::nullopt};
}

void InjectionModelRegistry::add(const std::string& name, Factory factory, std::string description, SceneKeys sceneKeys) {
  // A misspelt key would be reported as unread in every run of the engine: refused here, at registration.
  for (const std::string& key : sceneKeys)
    if (!sceneKeyNames().count(key))
      throw std::invalid_argument("injection model registry: \"" + name + "\" declares \"" + key +
                                  "\", which is not a scene key (SceneConfig.h)");
  add(name, std::move(factory), std::move(description));
  entries_[name].sceneKeys = std::move(sceneKeys);
}

bool InjectionModelRegistry::has(const std::string& name) const { return entries_.count(name) > 0; }

const InjectionModelRegistry::Entry& InjectionModelRegistry::at(const std::string& name) const {
  const auto it = entries_.find(name);
  if (it != entries_.end()) return it->second;
  std::string known;
  for (const auto& [n, e] : entries_) known += (known.empty() ? "\"" : ", \"") + n + "\"";
  throw std::invalid_argument("scene: pressure_model \"" + name + "\" is not an injection model of this build (it has " +
                              known + ")");
}

std::vector<std::string> InjectionModelRegistry::names() const {
  std::vector<std::string> n;
  for (const auto& [name, e] : entries_) n.push_back(name);
  return n;
}

const InjectionModelRegistry::SceneKeys& commonSceneKeys() {
  // What InjectionDriver.cpp reads whatever the engine: the presets (h/d, rest density), the tip and cannula
  // (the region, the markups, every engine's outlet), the flow and volume (the run's length), the viscosity
  // schedule, the region and the bone choice (threshold_hu, bone_model, cortical_hu), the snapshots, the
  // model's name.
  static const InjectionModelRegistry::SceneKeys keys{
      "scene_preset", "preset", "tip_mm", "direction", "cannula_inner_diameter_mm", "cannula_gauge",
      "cannula_length_mm", "cannula_wall", "flow_rate_ml_per_s", "volume_ml", "viscosity_pa_s",
      "viscosity_rate_pa_per_s", "viscosity_table", "threshold_hu", "roi_size_mm", "snapshot_interval_s",
      "simulated_ct_snapshots", "pressure_model", "bone_model", "cortical_hu"};
  return keys;
}

const InjectionModelRegistry::SceneKeys& modelChoiceSceneKeys() {
  // chooseModel's dimensionless numbers: the particle spacing (Re, St) and the sound speed (compression).
  static const InjectionModelRegistry::SceneKeys keys{"particle_radius_mm", "sound_speed_m_per_s"};
  return keys;
}

std::vector<std::string> sceneKeysNotRead(const SceneConfig& scene, const std::string& engine, const ModelChoice& choice,
                                          const InjectionModelRegistry& registry) {
  const InjectionModelRegistry::Entry& entry = registry.at(engine);
  if (!entry.sceneKeys) return {};
  const bool automatic = scene.pressureModel == "auto";
  // Why this engine: the scene forced it, or the automatic choice's reason (its first clause; metrics.json's
  // model_reason has the numbers).
  const std::string why = automatic ? "pressure_model \"auto\" chose it: " + choice.reason.substr(0, choice.reason.find(" ("))
                                    : "set by the scene key pressure_model";
  // The value each key has when not set: the scene preset's, under the scene's model preset (fixed_particle_sums'
  // default follows it).
  SceneConfig unset = scenePreset(scene.scenePreset);
  unset.modelPreset = scene.modelPreset;
  const json defaults = toJson(unset), given = toJson(scene);
  std::vector<std::string> warnings;
  for (const std::string& key : scene.explicitKeys) {
    if (commonSceneKeys().count(key) || entry.sceneKeys->count(key)) continue;
    if (automatic && modelChoiceSceneKeys().count(key)) continue;
    if (defaults.contains(key) && given.contains(key) && defaults[key] == given[key]) continue;
    std::string readers;
    for (const std::string& other : registry.names()) {
      const auto& keys = registry.at(other).sceneKeys;
      if (other != engine && keys && keys->count(key)) readers += (readers.empty() ? "" : ", ") + other;
    }
    warnings.push_back("scene key " + key + " does not apply to the " + engine + " model (chosen: " + why +
                       "); it was ignored" + (readers.empty() ? std::string() : " (it is read by: " + readers + ")"));
  }
  return warnings;
}

} // namespace cementsph::scene
