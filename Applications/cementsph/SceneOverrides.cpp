#include "SceneOverrides.h"

#include "cementsph/sph/Simulation.h"

#include <cmath>
#include <string>
#include <stdexcept>

namespace cementsph::app {

void addSceneOverrideOptions(CLI::App& sub, SceneOverrideArgs& a) {
  sub.add_option("--set", a.set, "Override a scene key: key=value (JSON value), repeatable");
  sub.add_option("--tip-mm", a.tipMm, "Override tip_mm: x,y,z")->delimiter(',')->expected(3);
  sub.add_option("--volume-ml", a.volumeMl, "Override volume_ml");
  sub.add_option("--flow-rate-ml-per-s", a.flowRateMlPerS, "Override flow_rate_ml_per_s");
  sub.add_option("--viscosity-pa-s", a.viscosityPaS, "Override viscosity_pa_s");
  sub.add_option("--snapshot-interval-s", a.snapshotIntervalS, "Override snapshot_interval_s");
  sub.add_option("--preset", a.preset, "Override the model preset (default, paper)");
}

scene::SceneSettings sceneSettings(const CLI::App& sub, const SceneOverrideArgs& a) {
  // A non-finite number is the option's fault, not the scene file's: name the option.
  auto requireFinite = [](const char* option, const std::vector<double>& values) {
    for (double x : values)
      if (!std::isfinite(x))
        throw std::invalid_argument(std::string(option) + ": " + exactNumber(x) + " is not a finite number");
  };
  requireFinite("--tip-mm", a.tipMm);
  requireFinite("--volume-ml", {a.volumeMl});
  requireFinite("--flow-rate-ml-per-s", {a.flowRateMlPerS});
  requireFinite("--viscosity-pa-s", {a.viscosityPaS});
  requireFinite("--snapshot-interval-s", {a.snapshotIntervalS});
  // A volume, rate, viscosity or interval given on the command line must be positive: refused here, the line
  // naming the option the user typed, rather than the scene key it becomes. (Limits that depend on other
  // keys, such as an injection longer than a day, are the scene's to check: SceneConfig::validate.)
  auto requirePositiveIfGiven = [&](const char* option, double x) {
    if (sub.count(option) && !(x > 0))
      throw std::invalid_argument(std::string(option) + ": " + exactNumber(x) + " is not a positive number");
  };
  requirePositiveIfGiven("--volume-ml", a.volumeMl);
  requirePositiveIfGiven("--flow-rate-ml-per-s", a.flowRateMlPerS);
  requirePositiveIfGiven("--viscosity-pa-s", a.viscosityPaS);
  requirePositiveIfGiven("--snapshot-interval-s", a.snapshotIntervalS);
  // Flags given on the command line override the scene file (and --set).
  scene::SceneSettings settings;
  settings.set = a.set;
  if (!a.tipMm.empty()) settings.tipMm = {a.tipMm[0], a.tipMm[1], a.tipMm[2]};
  if (sub.count("--volume-ml")) settings.volumeMl = a.volumeMl;
  if (sub.count("--flow-rate-ml-per-s")) settings.flowRateMlPerS = a.flowRateMlPerS;
  if (sub.count("--viscosity-pa-s")) settings.viscosityPaS = a.viscosityPaS;
  if (sub.count("--snapshot-interval-s")) settings.snapshotIntervalS = a.snapshotIntervalS;
  if (!a.preset.empty()) settings.modelPreset = a.preset;
  // A value the scene refuses (say a rate too slow for the volume) is then blamed on the option as typed.
  settings.optionOfKey = {{"tip_mm", "--tip-mm"},
                          {"volume_ml", "--volume-ml"},
                          {"flow_rate_ml_per_s", "--flow-rate-ml-per-s"},
                          {"viscosity_pa_s", "--viscosity-pa-s"},
                          {"snapshot_interval_s", "--snapshot-interval-s"},
                          {"preset", "--preset"}};
  return settings;
}

namespace {

// plan chooses the volume between --min-volume-ml and --max-volume-ml: a line about the volume to inject names
// those, not inject's --volume-ml, which plan does not have.
std::string namingPlanVolumes(const CLI::App& sub, std::string what) {
  const std::string injectVolume = "(volume_ml, --volume-ml)";
  const auto at = what.find(injectVolume);
  if (at != std::string::npos && !sub.get_option_no_throw("--volume-ml") && sub.get_option_no_throw("--max-volume-ml"))
    what.replace(at, injectVolume.size(), "(--min-volume-ml .. --max-volume-ml)");
  return what;
}

// The path --labels gave, or "".
std::string labelsPath(const CLI::App& sub) {
  const CLI::Option* labels = sub.get_option_no_throw("--labels");
  return labels && labels->count() > 0 ? labels->results().front() : std::string();
}

} // namespace

int namingTheOptions(const CLI::App& sub, const std::string& scenePath, const std::function<int()>& run) {
  try {
    return run();
  } catch (const std::invalid_argument& e) {
    const std::string what = namingPlanVolumes(sub, e.what()), labels = labelsPath(sub);
    if (!labels.empty()) {
      for (const std::string head : {"scene: labels_path ", "labels "})
        if (what.rfind(head, 0) == 0) throw std::invalid_argument("--labels " + what.substr(head.size()));
      if (what.rfind(labels + ": ", 0) == 0) throw std::invalid_argument("--labels " + what);
    }
    if (what.rfind("tip (", 0) == 0 && what.find("lies outside the CT") != std::string::npos) {
      const CLI::Option* tip = sub.get_option_no_throw("--tip-mm");
      if (tip && tip->count() > 0) throw std::invalid_argument("--tip-mm: " + what + ": give a tip inside the CT");
      throw std::invalid_argument(scenePath + ": key 'tip_mm': " + what + ": give a tip inside the CT");
    }
    if (what != e.what()) throw std::invalid_argument(what);
    throw;
  } catch (const sph::SimulationError& e) { // a failed run (status 2): "every one of the injections failed (...)"
    const std::string what = namingPlanVolumes(sub, e.what());
    if (what != e.what()) throw sph::SimulationError(what);
    throw;
  } catch (const std::runtime_error& e) {
    // The label map's reader refuses it starting with its path ("DIR: folder holds no DICOM series").
    const std::string labels = labelsPath(sub);
    if (!labels.empty() && std::string(e.what()).rfind(labels + ": ", 0) == 0)
      throw std::runtime_error("--labels " + std::string(e.what()));
    throw;
  }
}

} // namespace cementsph::app
