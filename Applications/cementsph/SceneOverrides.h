// The scene-override options that subcommands running an injection share (`inject`'s flags; `study` uses
// them through here): --set key=value (repeatable), --tip-mm, --volume-ml, --flow-rate-ml-per-s,
// --viscosity-pa-s, --snapshot-interval-s, --preset. They become the scene's settings (SceneConfig.h,
// SceneSettings: the --set list as given, the flags as typed fields) applied after the scene file: --set first,
// then the flags.
#pragma once

#include "cementsph/scene/SceneSettings.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace cementsph::app {

struct SceneOverrideArgs {
  std::vector<std::string> set;
  std::vector<double> tipMm;
  double volumeMl = 0, flowRateMlPerS = 0, viscosityPaS = 0, snapshotIntervalS = 0;
  std::string preset;
};

// Declares the options on `sub`, storing into *args (which must outlive the parse).
void addSceneOverrideOptions(CLI::App& sub, SceneOverrideArgs& args);

// The settings the command line asked for. Throws std::invalid_argument naming the option for a non-finite
// number or a volume, rate, viscosity or interval that is not positive.
scene::SceneSettings sceneSettings(const CLI::App& sub, const SceneOverrideArgs& args);

// Runs `run` (a command's work after its options are read); an error the modules word by the scene key a command
// line option set is worded by that option instead (std::invalid_argument): "scene: labels_path X" or "labels X"
// becomes "--labels X" when --labels was given, and "tip (...) lies outside the CT" names --tip-mm or the scene
// file's key tip_mm. The corpus of issue 21 found `inject --labels` blamed on labels_path and a tip outside the CT
// that named neither.
int namingTheOptions(const CLI::App& sub, const std::string& scenePath, const std::function<int()>& run);

// A double written so that it reads back exactly (the Scene module's, for the messages of both).
using scene::exactNumber;

} // namespace cementsph::app
