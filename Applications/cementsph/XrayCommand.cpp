// `cementsph xray`: X-ray (fluoroscopy) sequences of an injection, as the paper's Fig. 12 (Basafa et al.
// 2013): a DRR of every frame volume with one C-arm geometry (the options of `cementsph drr`), the cement
// segmented by subtracting the first frame and thresholding (XraySequence.h), its projected area over
// time, and, given a reference sequence (e.g. CTs of the experiment), the two compared frame by frame:
// Dice and IoU of the cement masks of frames matched by time (XraySequenceComparison.h).
//
// A sequence is an inject output folder written with the scene key simulated_ct_snapshots (its
// sequence.json lists the frame volumes and their times; frame 0 is the CT before any cement), or a list
// of volumes (--sequence a.nrrd,b.nrrd,...; times from --sequence-times-s, else 0, 1, 2, ... s).
// Writes DIR/sequence_drr_NNNN.nrrd (float DRR) + .png, the same for the reference (reference_drr_NNNN),
// sequence.csv, metrics.json, xray_frames.png (Fig. 12 style) and projected_area.png. Everything is
// computed first and written into a temporary sibling folder that is then moved into place, so bad input
// or a failed write leaves no partial output.
#include "cementsph/provenance/Provenance.h"
#include "CommandRegistry.h"
#include "CommandRequests.h"
#include "DrrOptions.h"

#include "cementsph/drr/XraySequence.h"
#include "cementsph/drr/XraySequenceComparison.h"
#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/rendering/RenderBackend.h"
#include "cementsph/rendering/ProjectedAreaPlot.h"
#include "cementsph/rendering/XrayFramesPicture.h"

#include <nlohmann/json.hpp>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

namespace {

namespace fs = std::filesystem;
namespace drr = cementsph::drr;
namespace rendering = cementsph::rendering;
using nlohmann::json;

// Outline / curve colours: simulation blue, reference orange (the surface picture's CT is beige, its
// simulation blue).
constexpr std::array<unsigned char, 3> kSequenceRgb{0, 110, 255}, kReferenceRgb{255, 120, 0};

std::string number(double x) {
  std::ostringstream s;
  s << std::setprecision(10) << x;
  return s.str();
}

// The frames of one sequence: volume paths and times.
struct FrameList {
  std::vector<std::string> paths;
  std::vector<double> timesS;
  std::string source; // for metrics.json: the folder or "list"
  std::optional<drr::Vec3> tipMm; // an inject folder's scene.json tip_mm
};

FrameList frameList(const std::vector<std::string>& values, const std::vector<double>& times, const std::string& option) {
  FrameList f;
  if (values.size() == 1 && fs::is_directory(values[0])) {
    const fs::path dir(values[0]), list = dir / "sequence.json";
    if (!fs::exists(list))
      throw std::runtime_error(values[0] + ": not an inject output folder with simulated CT snapshots (no "
                               "sequence.json: run inject with --set simulated_ct_snapshots=true), and one "
                               "volume is not a sequence");
    if (!times.empty())
      throw std::runtime_error(option + "-times-s: " + values[0] + " is an inject folder; its sequence.json gives the times");
    std::ifstream in(list);
    const json j = json::parse(in, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("frames") || !j["frames"].is_array())
      throw std::runtime_error(list.string() + ": not a sequence list (no \"frames\" array)");
    for (const json& frame : j["frames"]) {
      if (!frame.is_object() || !frame.contains("simulated_ct") || !frame["simulated_ct"].is_string() ||
          !frame.contains("time_s") || !frame["time_s"].is_number())
        throw std::runtime_error(list.string() + ": a frame lacks simulated_ct or time_s");
      f.paths.push_back((dir / frame["simulated_ct"].get<std::string>()).string());
      f.timesS.push_back(frame["time_s"].get<double>());
    }
    f.source = values[0];
    std::ifstream sceneFile(dir / "scene.json");
    const json scene = sceneFile ? json::parse(sceneFile, nullptr, false) : json();
    const json tip = scene.is_object() && scene.contains("tip_mm") ? scene["tip_mm"] : json();
    if (tip.is_array() && tip.size() == 3 && tip[0].is_number() && tip[1].is_number() && tip[2].is_number())
      f.tipMm = drr::Vec3{tip[0].get<double>(), tip[1].get<double>(), tip[2].get<double>()};
  } else {
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
  }
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
  return f;
}

// The sequence of the frames' DRRs; an error names the frame's file.
drr::XraySequence project(const FrameList& frames, const drr::XraySequenceOptions& options,
                          std::optional<cementsph::imaging::ImageType::Pointer> first = std::nullopt) {
  drr::XraySequence s(options);
  for (std::size_t k = 0; k < frames.paths.size(); ++k) {
    const auto volume = (k == 0 && first) ? *first : cementsph::imaging::readVolume(frames.paths[k]);
    try {
      s.addFrame(frames.timesS[k], cementsph::imaging::toVtk(volume.GetPointer()));
    } catch (const std::exception& e) {
      throw std::runtime_error(frames.paths[k] + ": " + e.what());
    }
  }
  return s;
}

double windowOf(const drr::XraySequence& s) {
  double top = 0.0;
  for (const auto& f : s.frames()) {
    double range[2];
    f.drr->GetPointData()->GetScalars()->GetRange(range, 0);
    top = std::max(top, range[1]);
  }
  return top;
}

std::string timeLabel(double t) {
  std::ostringstream s;
  s << "t = " << std::fixed << std::setprecision(1) << (std::abs(t) < 0.05 ? 0.0 : t) << " s";
  return s.str();
}

// Columns of the picture: at most maxColumns frames of the sequence, evenly spread, first and last included.
std::vector<std::size_t> pictureColumns(std::size_t frames, int maxColumns) {
  const std::size_t m = std::min<std::size_t>(frames, std::size_t(std::max(2, maxColumns)));
  std::vector<std::size_t> columns;
  for (std::size_t k = 0; k < m; ++k) {
    const auto index = std::size_t(std::lround(double(k) * double(frames - 1) / double(m - 1)));
    if (columns.empty() || columns.back() != index) columns.push_back(index);
  }
  return columns;
}

// The output folder is filled under a temporary sibling name and moved into place at the end.
class StagedFolder {
public:
  explicit StagedFolder(const fs::path& target) : target_(target) {
    fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    // Remember the outermost folder this run creates, so that a failure removes it again.
    for (fs::path p = parent; !p.empty() && !fs::exists(p); p = p.parent_path()) created_ = p;
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) throw std::runtime_error(parent.string() + ": cannot create the folder: " + ec.message());
    staging_ = parent / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()));
    fs::remove_all(staging_, ec);
    fs::create_directory(staging_, ec);
    if (ec) throw std::runtime_error(staging_.string() + ": cannot create the folder: " + ec.message());
  }
  ~StagedFolder() {
    if (published_) return;
    std::error_code ec;
    fs::remove_all(staging_, ec);
    if (!created_.empty()) fs::remove_all(created_, ec);
  }
  const fs::path& path() const { return staging_; }
  // Moves the files into the target (created when absent; files of the same name replaced). A folder in
  // the way of a file is found before anything moves.
  void publish() {
    for (const auto& entry : fs::directory_iterator(staging_))
      if (fs::is_directory(target_ / entry.path().filename()))
        throw std::runtime_error((target_ / entry.path().filename()).string() + " is a folder; nothing was written");
    if (!fs::exists(target_)) {
      fs::rename(staging_, target_);
    } else {
      // An earlier run's frames must not mix with this run's (it may have had more).
      cementsph::imaging::removeStaleOutputs(target_.string(), {"sequence_drr_####.nrrd", "sequence_drr_####.png",
                                                                "reference_drr_####.nrrd", "reference_drr_####.png"});
      for (const auto& entry : fs::directory_iterator(staging_))
        fs::rename(entry.path(), target_ / entry.path().filename());
      fs::remove(staging_);
    }
    published_ = true;
  }

private:
  fs::path target_, staging_, created_;
  bool published_ = false;
};

cementsph::app::CommandRunner setupXray(CLI::App& sub) {
  auto a = std::make_shared<cementsph::app::XrayRequest>();
  sub.add_option("--sequence", a->sequence,
                 "The frames: an inject output folder written with --set simulated_ct_snapshots=true, or "
                 "volumes in time order (a,b,c; the first is the background, before any cement)")
      ->required()
      ->delimiter(',');
  sub.add_option("--sequence-times-s", a->sequenceTimesS,
                 "Times of a list of volumes, s (default 0, 1, 2, ...; an inject folder has its own)")
      ->delimiter(',');
  sub.add_option("--reference", a->reference,
                 "A sequence to compare with (e.g. CTs of the experiment on the same patient frame), as --sequence")
      ->delimiter(',');
  sub.add_option("--reference-times-s", a->referenceTimesS, "Times of a reference list, s (default 0, 1, 2, ...)")
      ->delimiter(',');
  sub.add_option("--out", a->out,
                 "Output folder (created; files of the same name are replaced): sequence_drr_NNNN.nrrd/.png, "
                 "reference_drr_NNNN.nrrd/.png, sequence.csv, metrics.json, xray_frames.png, projected_area.png")
      ->required();
  cementsph::app::addDrrGeometryOptions(sub, a->drr,
                                        "Detector physical size, mm: height,width (default: fitted to the "
                                        "first frame's volume with a 10 % margin, square pixels)");
  sub.add_option("--cement-threshold-water-mm", a->thresholdWaterMm,
                 "Cement where a frame's DRR exceeds the first frame's by the attenuation of this much water, "
                 "mm (1 mm of water = 0.33 mm of cement 3000 HU above its surroundings)")
      ->capture_default_str();
  sub.add_option("--injection-point-mm", a->injectionPointMm,
                 "Keep only the cement region at this point's projection (x,y,z in the volumes' frame, mm; "
                 "an inject folder gives its tip_mm by default)")
      ->delimiter(',')
      ->expected(3);
  sub.add_option("--injection-search-radius-mm", a->searchRadiusMm,
                 "When no region contains the projected point, keep the nearest within this distance "
                 "(isocentre plane), mm")
      ->capture_default_str();
  sub.add_option("--match-tolerance-s", a->toleranceS,
                 "Frames of the two sequences match when their times differ by at most this, s (default: half "
                 "the shortest frame interval)");
  sub.add_option("--max-columns", a->maxColumns, "At most this many frames in xray_frames.png (first and last kept)")
      ->capture_default_str();
  sub.add_flag("--no-pictures", a->noPictures, "Do not write xray_frames.png and projected_area.png");

  return [a, &sub]() {
    a->toleranceGiven = sub.count("--match-tolerance-s") > 0;
    a->detectorSizeGiven = a->drr.sizeOption->count() > 0;
    return cementsph::app::runXray(*a);
  };
}

} // namespace

namespace cementsph::app {

int runXray(const XrayRequest& a) {
  const auto start = std::chrono::steady_clock::now();
  auto seconds = [](std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
  };
  // 1. Check everything that needs no file.
  (void)cementsph::app::checkedGeometry(a.drr);
  if (!(a.thresholdWaterMm > 0.0) || !std::isfinite(a.thresholdWaterMm))
    throw std::runtime_error("--cement-threshold-water-mm must be a positive number of mm");
  const bool toleranceGiven = a.toleranceGiven;
  if (toleranceGiven && !(a.toleranceS >= 0.0)) throw std::runtime_error("--match-tolerance-s must be 0 or more");
  if (a.reference.empty() && !a.referenceTimesS.empty())
    throw std::runtime_error("--reference-times-s needs --reference");
  if (a.maxColumns < 2) throw std::runtime_error("--max-columns must be 2 or more");
  if (!(a.searchRadiusMm >= 0.0)) throw std::runtime_error("--injection-search-radius-mm must be 0 or more");
  const fs::path out(a.out);
  if (fs::exists(out) && !fs::is_directory(out)) throw std::runtime_error(a.out + ": exists and is not a folder");
  const FrameList frames = frameList(a.sequence, a.sequenceTimesS, "--sequence");
  std::optional<FrameList> referenceFrames;
  if (!a.reference.empty()) referenceFrames = frameList(a.reference, a.referenceTimesS, "--reference");

  // 2. Geometry from the first frame, then the DRRs.
  auto t = std::chrono::steady_clock::now();
  const auto first = cementsph::imaging::readVolume(frames.paths[0]);
  const bool fitted = !a.detectorSizeGiven;
  drr::XraySequenceOptions options;
  options.geometry = cementsph::app::geometryForVolume(a.drr, cementsph::imaging::geometryOf(first).physicalBounds(), fitted);
  options.cementThresholdWaterMm = a.thresholdWaterMm;
  options.threads = a.drr.threads;
  if (!a.injectionPointMm.empty())
    options.injectionPointMm = drr::Vec3{a.injectionPointMm[0], a.injectionPointMm[1], a.injectionPointMm[2]};
  else
    options.injectionPointMm = frames.tipMm;
  options.injectionSearchRadiusMm = a.searchRadiusMm;
  const drr::XraySequence sequence = project(frames, options, first);
  std::optional<drr::XraySequence> reference;
  if (referenceFrames) reference = project(*referenceFrames, options);
  const double drrSeconds = seconds(t);
  std::optional<drr::XrayComparison> comparison;
  if (reference)
    comparison = drr::compareXraySequences(sequence, *reference, toleranceGiven ? std::optional<double>(a.toleranceS) : std::nullopt);

  // 3. Numbers: sequence.csv and metrics.json.
  std::ostringstream csv;
  csv << "time_s,projected_area_mm2,detector_area_mm2,cement_pixels";
  if (reference)
    csv << ",reference_time_s,reference_projected_area_mm2,reference_detector_area_mm2,reference_cement_pixels,dice,iou";
  csv << "\n";
  auto frameColumns = [](const drr::XrayFrame& f) {
    return number(f.timeS) + "," + number(f.projectedAreaMm2) + "," + number(f.detectorAreaMm2) + "," +
           std::to_string(f.cementPixels);
  };
  if (comparison) {
    for (const auto& p : comparison->pairs) {
      csv << (p.frame ? frameColumns(sequence.frames()[*p.frame]) : number(p.timeS) + ",,,") << ","
          << (p.reference ? frameColumns(reference->frames()[*p.reference]) : ",,,") << ","
          << (p.dice ? number(*p.dice) : "") << "," << (p.iou ? number(*p.iou) : "") << "\n";
    }
  } else {
    for (const auto& f : sequence.frames()) csv << frameColumns(f) << "\n";
  }

  const auto& g = options.geometry;
  json metrics;
  metrics["inputs"] = {{"sequence", frames.source == "list" ? json(frames.paths) : json(frames.source)},
                       {"reference", !referenceFrames ? json(nullptr)
                                     : referenceFrames->source == "list" ? json(referenceFrames->paths)
                                                                         : json(referenceFrames->source)}};
  metrics["geometry"] = {{"sad_mm", g.sadMm},
                         {"sid_mm", g.sidMm},
                         {"detector_pixels", {g.rows, g.cols}},
                         {"detector_size_mm", {g.heightMm, g.widthMm}},
                         {"detector_fitted_to_first_frame", fitted},
                         {"isocenter_mm", g.isocenterMm},
                         {"gantry_angle_deg", g.gantryAngleDeg},
                         {"parallel", g.parallel},
                         {"isocentre_magnification", g.isocentreMagnification()}};
  metrics["segmentation"] = {
      {"rule", "cement where DRR_k - DRR_0 > threshold (DRR_0: the first frame)"},
      {"cement_threshold_water_mm", a.thresholdWaterMm},
      {"cement_threshold_drr", sequence.thresholdDrr()},
      {"injection_point_mm", options.injectionPointMm ? json(*options.injectionPointMm) : json(nullptr)},
      {"injection_search_radius_mm", a.searchRadiusMm},
      {"component_rule", options.injectionPointMm ? "the 8-connected region at the injection point's projection "
                                                    "(else the nearest within the search radius)"
                                                  : "none: every pixel above the threshold"},
      {"drr_unit", "line integral of mu (1/mm) over mm, divided by 10 (plastimatch's)"}};
  metrics["projected_area_plane"] = "isocentre: detector area x (sad / sid)^2";
  metrics["frames"] = sequence.frames().size();
  metrics["final_time_s"] = sequence.frames().back().timeS;
  metrics["final_projected_area_mm2"] = sequence.frames().back().projectedAreaMm2;
  json warnings = json::array();
  if (reference) {
    metrics["reference_frames"] = reference->frames().size();
    metrics["final_reference_projected_area_mm2"] = reference->frames().back().projectedAreaMm2;
    metrics["match_tolerance_s"] = std::isfinite(comparison->toleranceS) ? json(comparison->toleranceS) : json(nullptr);
    metrics["matched_frames"] = comparison->matched();
    // The final frame of the sequence and the reference frame it matched.
    const auto last = std::find_if(comparison->pairs.rbegin(), comparison->pairs.rend(), [](const auto& p) { return p.frame.has_value(); });
    if (last->reference) {
      metrics["final_frame"] = {{"time_s", last->timeS},
                                {"reference_time_s", reference->frames()[*last->reference].timeS},
                                {"dice", *last->dice},
                                {"iou", *last->iou}};
    } else {
      metrics["final_frame"] = nullptr;
      warnings.push_back("the sequence's last frame matched no reference frame (see --match-tolerance-s)");
    }
  }
  metrics["warnings"] = warnings;

  // 4. Write everything into a staging folder, then move it into place.
  t = std::chrono::steady_clock::now();
  StagedFolder staged(out);
  const fs::path dir = staged.path();
  auto writeFrames = [&](const drr::XraySequence& s, const char* prefix) {
    const double window = windowOf(s);
    for (std::size_t k = 0; k < s.frames().size(); ++k) {
      char name[64];
      std::snprintf(name, sizeof name, "%s_drr_%04zu", prefix, k);
      const auto& frame = s.frames()[k];
      cementsph::imaging::writeVolume(cementsph::imaging::imageFromVtk(frame.drr), (dir / (std::string(name) + ".nrrd")).string());
      cementsph::app::writeDrrPng(frame.drr, (dir / (std::string(name) + ".png")).string(), window);
    }
  };
  writeFrames(sequence, "sequence");
  if (reference) writeFrames(*reference, "reference");
  cementsph::imaging::writeTextAtomically((dir / "sequence.csv").string(), csv.str());
  const double writeSeconds = seconds(t);

  // 5. Pictures (after the numbers; a failed picture is one line and exit status 3, as in `compare`).
  int status = 0;
  t = std::chrono::steady_clock::now();
  std::vector<std::string> pictures;
  if (!a.noPictures) {
    auto picture = [&](const char* name, const auto& draw) {
      try {
        draw(dir / name);
        pictures.push_back(name);
      } catch (const std::exception& e) {
        std::cerr << "cementsph xray: picture " << name << " not written (the numbers are): " << e.what() << "\n";
        status = 3;
      }
    };
    picture("xray_frames.png", [&](const fs::path& png) {
      std::vector<std::string> labels;
      rendering::XrayFramesRow simRow{"simulation", {}, kSequenceRgb, windowOf(sequence)};
      rendering::XrayFramesRow refRow{"reference", {}, kReferenceRgb, reference ? windowOf(*reference) : 0.0};
      for (std::size_t k : pictureColumns(sequence.frames().size(), a.maxColumns)) {
        const auto& f = sequence.frames()[k];
        labels.push_back(timeLabel(f.timeS));
        simRow.panels.push_back({f.drr, f.cementMask});
        if (!comparison) continue;
        rendering::XrayPanel panel; // empty: no reference frame at this instant
        for (const auto& p : comparison->pairs)
          if (p.frame == k && p.reference)
            panel = {reference->frames()[*p.reference].drr, reference->frames()[*p.reference].cementMask};
        refRow.panels.push_back(panel);
      }
      std::vector<rendering::XrayFramesRow> rows{simRow};
      if (comparison) rows.push_back(refRow);
      rendering::renderXrayFrames(rows, labels, png);
    });
    picture("projected_area.png", [&](const fs::path& png) {
      std::vector<rendering::ProjectedAreaSeries> series;
      const drr::XraySequence* ref = reference ? &*reference : nullptr;
      for (const drr::XraySequence* s : {&sequence, ref}) {
        if (s == nullptr) continue;
        // The reference's frames are measured instants: markers only (a line would invent values between).
        rendering::ProjectedAreaSeries curve{s == &sequence ? "simulation" : "reference", {}, {},
                                             s == &sequence ? kSequenceRgb : kReferenceRgb, s == &sequence};
        for (const auto& f : s->frames()) {
          curve.timeS.push_back(f.timeS);
          curve.areaMm2.push_back(f.projectedAreaMm2);
        }
        series.push_back(curve);
      }
      rendering::writeProjectedAreaPlot(series, png);
    });
  }
  const double pictureSeconds = seconds(t);
  metrics["pictures"] = pictures;
  if (const auto backend = rendering::lastRenderBackend()) metrics["render_backend"] = rendering::renderBackendName(*backend);
  metrics["timing_s"] = {{"drr_and_segmentation", drrSeconds}, {"write", writeSeconds},
                         {"pictures", pictureSeconds}, {"total", seconds(start)}};
  metrics["provenance"] = cementsph::provenance::toJson();
  cementsph::imaging::writeTextAtomically((dir / "metrics.json").string(), metrics.dump(2) + "\n");
  staged.publish();

  // 6. Summary.
  std::ostringstream s;
  s << "X-ray sequence: " << sequence.frames().size() << " frames, t " << frames.timesS.front() << " .. "
    << frames.timesS.back() << " s; detector " << g.rows << "x" << g.cols << " px, " << number(g.heightMm) << " x "
    << number(g.widthMm) << " mm" << (fitted ? " (fitted)" : "") << ", gantry " << g.gantryAngleDeg << " deg\n"
    << "final projected cement area " << number(sequence.frames().back().projectedAreaMm2)
    << " mm^2 at the isocentre (threshold " << a.thresholdWaterMm << " mm of water)\n";
  if (comparison) {
    s << "reference: " << reference->frames().size() << " frames, " << comparison->matched() << " matched by time";
    if (!metrics["final_frame"].is_null())
      s << "; final frame Dice " << number(metrics["final_frame"]["dice"].get<double>()) << ", IoU "
        << number(metrics["final_frame"]["iou"].get<double>());
    s << "\n";
  }
  s << "wrote " << (out / "sequence.csv").string() << ", metrics.json, DRR frames"
    << (pictures.empty() ? "" : ", pictures") << " (" << number(seconds(start)) << " s)\n";
  std::cout << s.str();
  for (const auto& w : warnings) std::cerr << "cementsph xray: warning: " << w.get<std::string>() << "\n";
  return status;
}

} // namespace cementsph::app

CEMENTSPH_REGISTER_COMMAND(xray_command, "xray",
                           "X-ray sequences (paper Fig. 12): DRRs of frame volumes, cement by first-frame "
                           "subtraction, projected area over time, Dice/IoU against a reference sequence",
                           setupXray)
