// The scene settings a command gives over a scene file (SceneConfig.h, loadSceneFile). Apart from SceneConfig.h,
// whose Eigen is not ITK's, so that a command's request can hold them in a file that includes ITK.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace cementsph::scene {

// What a command sets over the scene file, from its own options: the free-form `--set key=value` list (`set`,
// value in JSON, applied first, in order) and typed fields (inject's and study's --tip-mm, --volume-ml, ...;
// plan's entry; demo's plan), each set directly in the scene field of the key named beside it, after `set` (so
// a typed field wins over a --set of the same key), and recorded in explicitKeys as that key (the user set it).
// Only what is given is applied. (The constructor keeps a braced list of strings meaning the `set` list alone.)
struct SceneSettings {
  SceneSettings() {}
  std::vector<std::string> set;                   // "key=value"
  std::optional<std::array<double, 3>> tipMm;     // tip_mm [x, y, z]
  std::optional<std::array<double, 3>> direction; // direction [x, y, z]
  std::optional<double> volumeMl;                 // volume_ml
  std::optional<double> flowRateMlPerS;           // flow_rate_ml_per_s
  std::optional<double> viscosityPaS;             // viscosity_pa_s (a constant: replaces a viscosity_table)
  std::optional<double> snapshotIntervalS;        // snapshot_interval_s
  std::optional<bool> simulatedCtSnapshots;       // simulated_ct_snapshots
  std::optional<std::string> modelPreset;         // preset
  // The command-line option that gave a typed field, by its scene key (e.g. "viscosity_pa_s" ->
  // "--viscosity-pa-s"), so that a value the scene refuses is blamed on the option the user typed
  // ("--viscosity-pa-s 1e-09 (command line): ..."); a field without one reads "override key=value".
  std::map<std::string, std::string> optionOfKey;
};

// A double written so that it reads back exactly (17 significant digits): the form of a number in the
// messages about settings and options.
std::string exactNumber(double x);

} // namespace cementsph::scene
