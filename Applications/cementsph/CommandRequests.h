// Typed entry points of the subcommands that other subcommands run: `demo` runs inject, compare and xray,
// and `inject` its X-ray sequence. Each command's file fills its request from the command line and calls the
// same function, so no subcommand is re-entered through argv strings. Every field is an option of the
// command of the same name (`cementsph <command> --help`); the defaults are the options' defaults.
// Each returns the command's exit status and, when a result is asked for, fills it with the command's typed result
// (what its metrics.json is written from), so that a caller (demo) need not read back the file.
#pragma once

#include "DrrOptions.h"

#include "cementsph/drr/XraySequence.h"
#include "cementsph/drr/XraySequenceFiles.h"
#include "cementsph/imaging/CementSegmentation.h"
#include "cementsph/scene/SceneSettings.h"
#include "cementsph/surfacemetrics/Isosurface.h"

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

// The results the callers fill in, declared only: a command that runs none of them need not compile the
// injection's or the comparison's headers (InjectionRunner.h, CementComparison.h).
namespace cementsph::scene {
struct InjectionResult;
using InjectionRunResult = InjectionResult;
} // namespace cementsph::scene
namespace cementsph::study {
struct CementComparison;
} // namespace cementsph::study

namespace cementsph::app {

// `cementsph inject`.
struct InjectRequest {
  std::string ct, scene, out;
  std::string labels;                 // --labels: a label map on the CT's grid (scene key labels_path)
  scene::SceneSettings settings;      // --set and the scene flags, applied after the scene file
  int threads = 0;                    // 0: the cores the load average leaves free
  bool quiet = false, noPictures = false, allowLarge = false;
};
int runInject(const InjectRequest& request, scene::InjectionRunResult* result = nullptr);

// `cementsph compare`.
struct CompareRequest {
  std::string pre, post, simulated, out;
  std::vector<double> injection;    // injection point, mm (x, y, z)
  std::optional<double> thresholdHU; // --threshold-hu: a fixed difference threshold instead of half the contrast
  double closingMm = 0.0;
  double searchRadiusMm = imaging::SegmentationOptions{}.injectionSearchRadiusMm;
  double smoothingVoxels = surfacemetrics::IsosurfaceOptions{}.smoothingSigmaVoxels;
  bool noRegistration = false, noCementMask = false, noPictures = false;
};
int runCompare(const CompareRequest& request, study::CementComparison* result = nullptr);

// `cementsph xray`.
struct XrayRequest {
  XrayRequest() { drr.pixels = {256, 256}; }
  std::vector<std::string> sequence, reference;
  std::vector<double> sequenceTimesS, referenceTimesS;
  std::string out;
  DrrGeometryArgs drr;
  bool detectorSizeGiven = false; // else the detector is fitted to the first frame's volume
  double thresholdWaterMm = drr::XraySequenceOptions{}.cementThresholdWaterMm;
  double toleranceS = 0.0;
  bool toleranceGiven = false; // else half the shortest frame interval
  std::vector<double> injectionPointMm;
  double searchRadiusMm = drr::XraySequenceOptions{}.injectionSearchRadiusMm;
  int maxColumns = 6;
  bool noPictures = false;
  // The sequence's frames projected already (inject, as its run made them: InjectionRunOptions::onCtFrame) with the
  // options xraySequenceOptions gives for its first frame; null: the frames' volumes are read and projected here.
  std::shared_ptr<const drr::XraySequence> projected;
  double projectedSeconds = 0.0; // what projecting them took
};
int runXray(const XrayRequest& request, drr::XrayHeadline* headline = nullptr);
// The options `xray` projects a sequence with: the geometry for its first frame's voxel-centre bounds (the detector
// fitted to them unless its size was given), the cement threshold, the threads, the injection point (given, else
// tipMm: an inject folder's tip).
drr::XraySequenceOptions xraySequenceOptions(const XrayRequest& request, const std::array<double, 6>& firstFrameBoundsMm,
                                             const std::optional<drr::Vec3>& tipMm);

} // namespace cementsph::app
