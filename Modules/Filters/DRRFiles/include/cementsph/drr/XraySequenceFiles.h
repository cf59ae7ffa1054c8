// The files of an X-ray sequence run (`cementsph xray`, paper Fig. 12): the frame list it reads (an inject
// output folder's sequence.json, or a list of volumes with their times) and the tables it writes
// (sequence.csv, metrics.json). The schemas live here, beside the sequence they describe, so the command
// only parses options and prints a summary.
#pragma once

#include "cementsph/drr/XraySequence.h"
#include "cementsph/drr/XraySequenceComparison.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cementsph::drr {

// The frames of one sequence: volume paths and times.
struct XrayFrameList {
  std::vector<std::string> paths;
  std::vector<double> timesS;
  std::string source;         // metrics.json's inputs: the folder, or "list"
  std::optional<Vec3> tipMm;  // an inject folder's scene.json tip_mm
};

// values: one inject output folder (with sequence.json: {"frames": [{"simulated_ct": NAME, "time_s": T}, ...]}
// and, optionally, scene.json's tip_mm), or volume paths in time order with times (empty: 0, 1, 2, ... s).
// option names the command-line option in errors ("--sequence"; its times option is option + "-times-s").
// Throws std::runtime_error naming the file or option for: a folder without sequence.json, times given for a
// folder, a malformed list, a count of times that differs from the volumes', fewer than 2 frames, times that
// are not finite or do not increase, a frame file that does not exist.
XrayFrameList readXrayFrameList(const std::vector<std::string>& values, const std::vector<double>& times,
                                const std::string& option);

// sequence.csv: one row per frame (time, projected and detector area, cement pixels); with a comparison, one
// row per frame pair with the reference's columns and Dice / IoU (empty where a frame matched nothing).
std::string xraySequenceCsv(const XraySequence& sequence, const XraySequence* reference,
                            const XrayComparison* comparison);
// Writes it to file, atomically.
void writeXraySequenceCsv(const XraySequence& sequence, const XraySequence* reference,
                          const XrayComparison* comparison, const std::filesystem::path& file);

// What a run did, for metrics.json.
struct XrayRunRecord {
  const XrayFrameList* frames = nullptr;
  const XrayFrameList* referenceFrames = nullptr; // none: no reference
  const XraySequenceOptions* options = nullptr;
  bool detectorFitted = false; // the detector size was fitted to the first frame's volume
  const XraySequence* sequence = nullptr;
  const XraySequence* reference = nullptr;
  const XrayComparison* comparison = nullptr;
  std::vector<std::string> pictures;
  std::optional<std::string> renderBackend;
  double drrSeconds = 0, writeSeconds = 0, pictureSeconds = 0, totalSeconds = 0;
};

// The warnings of a comparison (its last frame matched no reference frame), for metrics.json and stderr.
std::vector<std::string> xrayComparisonWarnings(const XrayComparison* comparison);

// metrics.json without its provenance: inputs, geometry, segmentation rule, frame counts and final areas, the
// final frame's Dice / IoU, warnings, pictures, timing.
nlohmann::json xrayMetricsJson(const XrayRunRecord& run);

// Writes metrics.json (xrayMetricsJson with the program's provenance) to file, atomically.
void writeXrayMetrics(const XrayRunRecord& run, const std::filesystem::path& file);

// A run's headline figures, as metrics.json holds them (final_time_s, final_projected_area_mm2,
// final_reference_projected_area_mm2, final_frame's dice and iou), for a caller that gathers them (demo).
// The reference's figures are empty without a reference; the final frame's when the sequence's last frame
// matched no reference frame.
struct XrayHeadline {
  double finalTimeS = 0, finalProjectedAreaMm2 = 0;
  std::optional<double> finalReferenceProjectedAreaMm2, finalFrameDice, finalFrameIou;
};
XrayHeadline xrayHeadline(const XrayRunRecord& run);

} // namespace cementsph::drr
