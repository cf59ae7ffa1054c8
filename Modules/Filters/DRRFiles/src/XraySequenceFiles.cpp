#include "cementsph/drr/XraySequenceFiles.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/provenance/Provenance.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace cementsph::drr {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Ten significant digits: the tables' numbers (the same text the command has always written).
std::string number(double x) {
  std::ostringstream s;
  s << std::setprecision(10) << x;
  return s.str();
}

// An inject output folder: sequence.json lists the frame volumes and their times; scene.json gives the tip.
XrayFrameList readInjectFolder(const std::string& folder, const std::vector<double>& times, const std::string& option) {
  const fs::path dir(folder), list = dir / "sequence.json";
  if (!fs::exists(list))
    throw std::runtime_error(folder + ": not an inject output folder with simulated CT snapshots (no "
                             "sequence.json: run inject with --set simulated_ct_snapshots=true), and one "
                             "volume is not a sequence");
  if (!times.empty())
    throw std::runtime_error(option + "-times-s: " + folder + " is an inject folder; its sequence.json gives the times");
  std::ifstream in(list);
  const json j = json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("frames") || !j["frames"].is_array())
    throw std::runtime_error(list.string() + ": not a sequence list (no \"frames\" array)");
  XrayFrameList f;
  for (const json& frame : j["frames"]) {
    if (!frame.is_object() || !frame.contains("simulated_ct") || !frame["simulated_ct"].is_string() ||
        !frame.contains("time_s") || !frame["time_s"].is_number())
      throw std::runtime_error(list.string() + ": a frame lacks simulated_ct or time_s");
    f.paths.push_back((dir / frame["simulated_ct"].get<std::string>()).string());
    f.timesS.push_back(frame["time_s"].get<double>());
  }
  f.source = folder;
  std::ifstream sceneFile(dir / "scene.json");
  const json scene = sceneFile ? json::parse(sceneFile, nullptr, false) : json();
  const json tip = scene.is_object() && scene.contains("tip_mm") ? scene["tip_mm"] : json();
  if (tip.is_array() && tip.size() == 3 && tip[0].is_number() && tip[1].is_number() && tip[2].is_number())
    f.tipMm = Vec3{tip[0].get<double>(), tip[1].get<double>(), tip[2].get<double>()};
  return f;
}

XrayFrameList volumeList(const std::vector<std::string>& values, const std::vector<double>& times, const std::string& option) {
  XrayFrameList f;
  f.paths = values;
  f.source = "list";
  if (times.empty()) {
    for (std::size_t k = 0; k < values.size(); ++k) f.timesS.push_back(double(k));
  } else if (times.size() != values.size()) {
    throw std::runtime_error(option + "-times-s: " + std::to_string(times.size()) + " times for " +
                             std::to_string(values.size()) + " volumes");
  } else {
    f.timesS = times;
  }
  return f;
}

void checkFrameList(const XrayFrameList& f, const std::string& option) {
  if (f.paths.size() < 2)
    throw std::runtime_error(option + ": a sequence needs at least 2 frames (the first is the background)");
  for (std::size_t k = 0; k < f.timesS.size(); ++k) {
    if (!std::isfinite(f.timesS[k])) throw std::runtime_error(option + ": frame time " + std::to_string(k) + " is not finite");
    if (k > 0 && !(f.timesS[k] > f.timesS[k - 1]))
      throw std::runtime_error(option + ": frame times must increase (" + number(f.timesS[k]) + " s after " +
                               number(f.timesS[k - 1]) + " s)");
  }
  for (const std::string& p : f.paths)
    if (!fs::exists(p)) throw std::runtime_error(p + ": no such file or folder");
}

std::string frameColumns(const XrayFrame& f) {
  return number(f.timeS) + "," + number(f.projectedAreaMm2) + "," + number(f.detectorAreaMm2) + "," +
         std::to_string(f.cementPixels);
}

json inputsJson(const XrayRunRecord& run) {
  auto source = [](const XrayFrameList& f) { return f.source == "list" ? json(f.paths) : json(f.source); };
  return {{"sequence", source(*run.frames)},
          {"reference", run.referenceFrames ? source(*run.referenceFrames) : json(nullptr)}};
}

json geometryJson(const DRRGeometry& g, bool fitted) {
  return {{"sad_mm", g.sadMm},
          {"sid_mm", g.sidMm},
          {"detector_pixels", {g.rows, g.cols}},
          {"detector_size_mm", {g.heightMm, g.widthMm}},
          {"detector_fitted_to_first_frame", fitted},
          {"isocenter_mm", g.isocenterMm},
          {"gantry_angle_deg", g.gantryAngleDeg},
          {"parallel", g.parallel},
          {"isocentre_magnification", g.isocentreMagnification()}};
}

json segmentationJson(const XraySequenceOptions& options, const XraySequence& sequence) {
  const bool atPoint = options.injectionPointMm.has_value();
  return {{"rule", "cement where DRR_k - DRR_0 > threshold (DRR_0: the first frame)"},
          {"cement_threshold_water_mm", options.cementThresholdWaterMm},
          {"cement_threshold_drr", sequence.thresholdDrr()},
          {"injection_point_mm", atPoint ? json(*options.injectionPointMm) : json(nullptr)},
          {"injection_search_radius_mm", options.injectionSearchRadiusMm},
          {"component_rule", atPoint ? "the 8-connected region at the injection point's projection "
                                       "(else the nearest within the search radius)"
                                     : "none: every pixel above the threshold"},
          {"drr_unit", "line integral of mu (1/mm) over mm, divided by 10 (plastimatch's)"}};
}

// The sequence's last frame and the reference frame it matched (none when it matched none).
const XrayFramePair* lastFramePair(const XrayComparison& comparison) {
  const auto last = std::find_if(comparison.pairs.rbegin(), comparison.pairs.rend(),
                                 [](const XrayFramePair& p) { return p.frame.has_value(); });
  return last == comparison.pairs.rend() ? nullptr : &*last;
}

void addComparison(json& metrics, const XrayRunRecord& run) {
  const XrayComparison& comparison = *run.comparison;
  metrics["reference_frames"] = run.reference->frames().size();
  metrics["final_reference_projected_area_mm2"] = run.reference->frames().back().projectedAreaMm2;
  metrics["match_tolerance_s"] = std::isfinite(comparison.toleranceS) ? json(comparison.toleranceS) : json(nullptr);
  metrics["matched_frames"] = comparison.matched();
  const XrayFramePair* last = lastFramePair(comparison);
  if (last && last->reference) {
    metrics["final_frame"] = {{"time_s", last->timeS},
                              {"reference_time_s", run.reference->frames()[*last->reference].timeS},
                              {"dice", *last->dice},
                              {"iou", *last->iou}};
  } else {
    metrics["final_frame"] = nullptr;
  }
}

} // namespace

XrayFrameList readXrayFrameList(const std::vector<std::string>& values, const std::vector<double>& times,
                                const std::string& option) {
  const bool folder = values.size() == 1 && fs::is_directory(values[0]);
  XrayFrameList f = folder ? readInjectFolder(values[0], times, option) : volumeList(values, times, option);
  checkFrameList(f, option);
  return f;
}

std::string xraySequenceCsv(const XraySequence& sequence, const XraySequence* reference,
                            const XrayComparison* comparison) {
  std::ostringstream csv;
  csv << "time_s,projected_area_mm2,detector_area_mm2,cement_pixels";
  if (comparison)
    csv << ",reference_time_s,reference_projected_area_mm2,reference_detector_area_mm2,reference_cement_pixels,dice,iou";
  csv << "\n";
  if (!comparison) {
    for (const auto& f : sequence.frames()) csv << frameColumns(f) << "\n";
    return csv.str();
  }
  for (const auto& p : comparison->pairs) {
    csv << (p.frame ? frameColumns(sequence.frames()[*p.frame]) : number(p.timeS) + ",,,") << ","
        << (p.reference ? frameColumns(reference->frames()[*p.reference]) : ",,,") << ","
        << (p.dice ? number(*p.dice) : "") << "," << (p.iou ? number(*p.iou) : "") << "\n";
  }
  return csv.str();
}

void writeXraySequenceCsv(const XraySequence& sequence, const XraySequence* reference,
                          const XrayComparison* comparison, const fs::path& file) {
  imaging::writeTextAtomically(file.string(), xraySequenceCsv(sequence, reference, comparison));
}

std::vector<std::string> xrayComparisonWarnings(const XrayComparison* comparison) {
  if (!comparison) return {};
  const XrayFramePair* last = lastFramePair(*comparison);
  if (last && last->reference) return {};
  return {"the sequence's last frame matched no reference frame (see --match-tolerance-s)"};
}

json xrayMetricsJson(const XrayRunRecord& run) {
  const XraySequence& sequence = *run.sequence;
  json metrics;
  metrics["inputs"] = inputsJson(run);
  metrics["geometry"] = geometryJson(run.options->geometry, run.detectorFitted);
  metrics["segmentation"] = segmentationJson(*run.options, sequence);
  metrics["projected_area_plane"] = "isocentre: detector area x (sad / sid)^2";
  metrics["frames"] = sequence.frames().size();
  metrics["final_time_s"] = sequence.frames().back().timeS;
  metrics["final_projected_area_mm2"] = sequence.frames().back().projectedAreaMm2;
  if (run.comparison) addComparison(metrics, run);
  metrics["warnings"] = xrayComparisonWarnings(run.comparison);
  metrics["pictures"] = run.pictures;
  if (run.renderBackend) metrics["render_backend"] = *run.renderBackend;
  metrics["timing_s"] = {{"drr_and_segmentation", run.drrSeconds}, {"write", run.writeSeconds},
                         {"pictures", run.pictureSeconds}, {"total", run.totalSeconds}};
  return metrics;
}

void writeXrayMetrics(const XrayRunRecord& run, const fs::path& file) {
  json metrics = xrayMetricsJson(run);
  metrics["provenance"] = provenance::toJson();
  imaging::writeTextAtomically(file.string(), metrics.dump(2) + "\n");
}

XrayHeadline xrayHeadline(const XrayRunRecord& run) {
  const XraySequence& sequence = *run.sequence;
  XrayHeadline h;
  h.finalTimeS = sequence.frames().back().timeS;
  h.finalProjectedAreaMm2 = sequence.frames().back().projectedAreaMm2;
  if (!run.comparison) return h;
  h.finalReferenceProjectedAreaMm2 = run.reference->frames().back().projectedAreaMm2;
  if (const XrayFramePair* last = lastFramePair(*run.comparison); last && last->reference) {
    h.finalFrameDice = *last->dice;
    h.finalFrameIou = *last->iou;
  }
  return h;
}

} // namespace cementsph::drr
