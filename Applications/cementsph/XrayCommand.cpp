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
//
// A thin layer: the frame lists, sequence.csv and metrics.json are CementSPH::DRR's (XraySequenceFiles.h), the
// staged output folder ImagingIO's (StagedFolder.h); this file parses the options, runs the steps in order
// and prints the summary.
#include "CommandRegistry.h"
#include "CommandRequests.h"
#include "DrrOptions.h"
#include "OutputFiles.h"

#include "cementsph/drr/DRRFiles.h"
#include "cementsph/drr/XraySequence.h"
#include "cementsph/drr/XraySequenceComparison.h"
#include "cementsph/drr/XraySequenceFiles.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/StagedFolder.h"
#include "cementsph/scene/SceneSettings.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/rendering/RenderBackend.h"
#include "cementsph/rendering/ProjectedAreaPlot.h"
#include "cementsph/rendering/XrayFramesLayout.h"
#include "cementsph/rendering/XrayFramesPicture.h"
#include "cementsph/study/ScanProvenance.h"

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

namespace {

namespace fs = std::filesystem;
namespace drr = cementsph::drr;
namespace study = cementsph::study;
namespace rendering = cementsph::rendering;
using cementsph::app::XrayRequest;

std::string number(double x) {
  std::ostringstream s;
  s << std::setprecision(10) << x;
  return s.str();
}

double secondsSince(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// The sequence of the frames' DRRs; an error names the frame's file.
drr::XraySequence project(const drr::XrayFrameList& frames, const drr::XraySequenceOptions& options,
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

// Times given on the command line increase, the line naming the option that holds them (the frame list's own
// check names --sequence, which held the volumes, not the times).
void checkIncreasingTimes(const std::vector<double>& timesS, const char* option) {
  for (std::size_t k = 1; k < timesS.size(); ++k)
    if (!(timesS[k] > timesS[k - 1]))
      throw std::runtime_error(std::string(option) + ": frame times must increase, one per volume (" +
                               cementsph::scene::exactNumber(timesS[k]) + " s after " +
                               cementsph::scene::exactNumber(timesS[k - 1]) + " s)");
}

// Everything that needs no file.
void checkRequest(const XrayRequest& a) {
  checkIncreasingTimes(a.sequenceTimesS, "--sequence-times-s");
  checkIncreasingTimes(a.referenceTimesS, "--reference-times-s");
  (void)cementsph::app::checkedGeometry(a.drr);
  if (!(a.thresholdWaterMm > 0.0) || !std::isfinite(a.thresholdWaterMm))
    throw std::runtime_error("--cement-threshold-water-mm must be a positive number of mm");
  if (a.toleranceGiven && !(a.toleranceS >= 0.0)) throw std::runtime_error("--match-tolerance-s must be 0 or more");
  if (a.reference.empty() && !a.referenceTimesS.empty())
    throw std::runtime_error("--reference-times-s needs --reference");
  if (a.maxColumns < 2) throw std::runtime_error("--max-columns must be 2 or more");
  if (!(a.searchRadiusMm >= 0.0)) throw std::runtime_error("--injection-search-radius-mm must be 0 or more");
  if (fs::exists(a.out) && !fs::is_directory(a.out)) throw std::runtime_error(a.out + ": exists and is not a folder");
}

// The run's inputs and what it computed.
struct XrayRun {
  drr::XrayFrameList frames;
  std::optional<drr::XrayFrameList> referenceFrames;
  drr::XraySequenceOptions options;
  bool fitted = false;
  std::optional<drr::XraySequence> sequence, reference;
  std::optional<drr::XrayComparison> comparison;
  double drrSeconds = 0.0;
};

// Geometry from the first frame, then the DRRs (or those made already) and their comparison.
void computeSequences(const XrayRequest& a, XrayRun& run) {
  const auto t = std::chrono::steady_clock::now();
  run.fitted = !a.detectorSizeGiven;
  if (a.projected) {
    if (a.projected->frames().size() != run.frames.paths.size())
      throw std::runtime_error("the sequence projected in memory has " + std::to_string(a.projected->frames().size()) +
                               " frames, its frame list " + std::to_string(run.frames.paths.size()));
    run.options = a.projected->options();
    run.sequence = *a.projected;
  } else {
    const auto first = cementsph::imaging::readVolume(run.frames.paths[0]);
    run.options = cementsph::app::xraySequenceOptions(a, cementsph::imaging::geometryOf(first).physicalBounds(),
                                                      run.frames.tipMm);
    run.sequence = project(run.frames, run.options, first);
  }
  if (run.referenceFrames) run.reference = project(*run.referenceFrames, run.options);
  run.drrSeconds = secondsSince(t) + a.projectedSeconds;
  if (run.reference)
    run.comparison = drr::compareXraySequences(
        *run.sequence, *run.reference, a.toleranceGiven ? std::optional<double>(a.toleranceS) : std::nullopt);
}

// xray_frames.png: the sequence's frames (at most maxColumns) above the reference frames they matched.
// The reference row is named by what its volumes are (ScanProvenance.h): a phantom's scans are simulated.
void drawFrames(const XrayRun& run, int maxColumns, const std::string& referenceLabel, const fs::path& png) {
  const drr::XraySequence& sequence = *run.sequence;
  std::vector<std::string> labels;
  rendering::XrayFramesRow simRow{"simulation", {}, rendering::kXraySequenceRgb, drr::drrWindow(sequence)};
  rendering::XrayFramesRow refRow{referenceLabel, {}, rendering::kXrayReferenceRgb,
                                  run.reference ? drr::drrWindow(*run.reference) : 0.0};
  for (std::size_t k : rendering::xrayFrameColumns(sequence.frames().size(), maxColumns)) {
    const auto& f = sequence.frames()[k];
    labels.push_back(rendering::xrayTimeLabel(f.timeS));
    simRow.panels.push_back({f.drr, f.cementMask});
    if (!run.comparison) continue;
    rendering::XrayPanel panel; // empty: no reference frame at this instant
    for (const auto& p : run.comparison->pairs)
      if (p.frame == k && p.reference)
        panel = {run.reference->frames()[*p.reference].drr, run.reference->frames()[*p.reference].cementMask};
    refRow.panels.push_back(panel);
  }
  std::vector<rendering::XrayFramesRow> rows{simRow};
  if (run.comparison) rows.push_back(refRow);
  rendering::renderXrayFrames(rows, labels, png);
}

// projected_area.png: the projected cement area over time.
void drawProjectedArea(const XrayRun& run, const std::string& referenceLabel, const fs::path& png) {
  std::vector<rendering::ProjectedAreaSeries> series;
  const drr::XraySequence* sequence = &*run.sequence;
  const drr::XraySequence* ref = run.reference ? &*run.reference : nullptr;
  for (const drr::XraySequence* s : {sequence, ref}) {
    if (s == nullptr) continue;
    // The reference's frames are measured instants: markers only (a line would invent values between).
    rendering::ProjectedAreaSeries curve{s == sequence ? "simulation" : referenceLabel, {}, {},
                                         s == sequence ? rendering::kXraySequenceRgb : rendering::kXrayReferenceRgb,
                                         s == sequence};
    for (const auto& f : s->frames()) {
      curve.timeS.push_back(f.timeS);
      curve.areaMm2.push_back(f.projectedAreaMm2);
    }
    series.push_back(curve);
  }
  rendering::writeProjectedAreaPlot(series, png);
}

void printSummary(const XrayRequest& a, const XrayRun& run, const drr::XrayRunRecord& record) {
  const drr::XraySequence& sequence = *run.sequence;
  const auto& g = run.options.geometry;
  std::ostringstream s;
  s << "X-ray sequence: " << sequence.frames().size() << " frames, t " << run.frames.timesS.front() << " .. "
    << run.frames.timesS.back() << " s; detector " << g.rows << "x" << g.cols << " px, " << number(g.heightMm)
    << " x " << number(g.widthMm) << " mm" << (run.fitted ? " (fitted)" : "") << ", gantry " << g.gantryAngleDeg
    << " deg\n"
    << "final projected cement area " << number(sequence.frames().back().projectedAreaMm2)
    << " mm^2 at the isocentre (threshold " << a.thresholdWaterMm << " mm of water)\n";
  const std::vector<std::string> warnings = drr::xrayComparisonWarnings(record.comparison);
  if (run.comparison) {
    s << "reference: " << run.reference->frames().size() << " frames, " << run.comparison->matched()
      << " matched by time";
    const auto last = std::find_if(run.comparison->pairs.rbegin(), run.comparison->pairs.rend(),
                                   [](const auto& p) { return p.frame.has_value(); });
    if (warnings.empty()) s << "; final frame Dice " << number(*last->dice) << ", IoU " << number(*last->iou);
    s << "\n";
  }
  s << "wrote " << (fs::path(a.out) / "sequence.csv").string() << ", metrics.json, DRR frames"
    << (record.pictures.empty() ? "" : ", pictures") << " (" << number(record.totalSeconds) << " s)\n";
  std::cout << s.str();
  for (const auto& w : warnings) std::cerr << "cementsph xray: warning: " << w << "\n";
}

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

drr::XraySequenceOptions xraySequenceOptions(const XrayRequest& a, const std::array<double, 6>& firstFrameBoundsMm,
                                             const std::optional<drr::Vec3>& tipMm) {
  drr::XraySequenceOptions options;
  options.geometry = geometryForVolume(a.drr, firstFrameBoundsMm, !a.detectorSizeGiven);
  options.cementThresholdWaterMm = a.thresholdWaterMm;
  options.threads = a.drr.threads;
  if (!a.injectionPointMm.empty())
    options.injectionPointMm = drr::Vec3{a.injectionPointMm[0], a.injectionPointMm[1], a.injectionPointMm[2]};
  else
    options.injectionPointMm = tipMm;
  options.injectionSearchRadiusMm = a.searchRadiusMm;
  return options;
}

int runXray(const XrayRequest& a, drr::XrayHeadline* headline) {
  const auto start = std::chrono::steady_clock::now();
  checkRequest(a);
  XrayRun run;
  run.frames = drr::readXrayFrameList(a.sequence, a.sequenceTimesS, "--sequence");
  if (!a.reference.empty()) run.referenceFrames = drr::readXrayFrameList(a.reference, a.referenceTimesS, "--reference");
  computeSequences(a, run);
  drr::XrayRunRecord record;
  record.frames = &run.frames;
  record.referenceFrames = run.referenceFrames ? &*run.referenceFrames : nullptr;
  record.options = &run.options;
  record.detectorFitted = run.fitted;
  record.sequence = &*run.sequence;
  record.reference = run.reference ? &*run.reference : nullptr;
  record.comparison = run.comparison ? &*run.comparison : nullptr;
  record.drrSeconds = run.drrSeconds;

  // Everything goes into a staging folder that is moved into place at the end.
  auto t = std::chrono::steady_clock::now();
  imaging::StagedFolder staged(a.out);
  const fs::path dir = staged.path();
  drr::writeDrrFrames(*run.sequence, "sequence", dir);
  if (run.reference) drr::writeDrrFrames(*run.reference, "reference", dir);
  drr::writeXraySequenceCsv(*run.sequence, record.reference, record.comparison, dir / "sequence.csv");
  record.writeSeconds = secondsSince(t);

  // Pictures after the numbers; a failed picture is one line and exit status 3, as in `compare`.
  t = std::chrono::steady_clock::now();
  PictureSteps pictures("xray");
  const std::string referenceLabel =
      run.referenceFrames ? study::referenceScansLabel(run.referenceFrames->paths) : std::string("reference");
  if (!a.noPictures) {
    pictures.draw("xray_frames.png", dir / "xray_frames.png",
                  [&](const fs::path& png) { drawFrames(run, a.maxColumns, referenceLabel, png); });
    pictures.draw("projected_area.png", dir / "projected_area.png",
                  [&](const fs::path& png) { drawProjectedArea(run, referenceLabel, png); });
  }
  record.pictureSeconds = secondsSince(t);
  record.pictures = pictures.written();
  if (const auto backend = rendering::lastRenderBackend()) record.renderBackend = rendering::renderBackendName(*backend);
  record.totalSeconds = secondsSince(start) + a.projectedSeconds; // with the projections made beforehand
  drr::writeXrayMetrics(record, dir / "metrics.json");
  staged.publish({"sequence_drr_####.nrrd", "sequence_drr_####.png", "reference_drr_####.nrrd",
                  "reference_drr_####.png"});
  record.totalSeconds = secondsSince(start) + a.projectedSeconds;
  if (headline) *headline = drr::xrayHeadline(record);
  printSummary(a, run, record);
  return pictures.status();
}

} // namespace cementsph::app

CEMENTSPH_REGISTER_COMMAND(xray_command, "xray",
                           "X-ray sequences (paper Fig. 12): DRRs of frame volumes, cement by first-frame "
                           "subtraction, projected area over time, Dice/IoU against a reference sequence",
                           setupXray)
