// The scene-override options that subcommands running an injection share (`inject`'s flags; `study` uses
// them through here): --set key=value (repeatable), --tip-mm, --volume-ml, --flow-rate-ml-per-s,
// --viscosity-pa-s, --snapshot-interval-s, --preset. They become the scene's settings (SceneConfig.h,
// SceneSettings: the --set list as given, the flags as typed fields) applied after the scene file: --set first,
// then the flags.
#pragma once

#include "cementsph/scene/SceneSettings.h"

#include <CLI/CLI.hpp>

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

// A double written so that it reads back exactly (the Scene module's, for the messages of both).
using scene::exactNumber;

} // namespace cementsph::app
