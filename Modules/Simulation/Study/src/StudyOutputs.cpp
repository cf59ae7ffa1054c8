// AlignedPost.h (ITK transforms, with ITK's bundled Eigen Geometry) must come before the system Eigen of
// SceneConfig.h.
#include "cementsph/study/AlignedPost.h"

#include "cementsph/study/StudyOutputs.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/provenance/Provenance.h"
#include "cementsph/scene/RunEstimate.h"
#include "cementsph/scene/SceneConfig.h"
#include "cementsph/study/StudyReport.h"

#include <cstdio>
#include <stdexcept>

namespace cementsph::study {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string fmt(double x, const char* format) {
  char buf[48];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

// study.md's opening paragraphs: the inputs as run, the segmentation, the reference, the time so far.
std::vector<std::string> studyPreamble(const StudyRecord& r) {
  const scene::SceneConfig& s = r.plan->baseScene;
  std::vector<std::string> preamble{
      "CT `" + r.ct + "`; scene `" + r.sceneFile + "` as run: " + fmt(s.volumeMl, "%g") + " ml at " +
          fmt(s.flowRateMlPerS, "%g") + " ml/s, " + fmt(s.viscosityPaS, "%g") + " Pa.s, model preset " +
          s.modelPreset + ", tip (" + fmt((*s.tipMm)[0], "%g") + ", " + fmt((*s.tipMm)[1], "%g") + ", " +
          fmt((*s.tipMm)[2], "%g") + ") mm; " + std::to_string(r.threads) + " OpenMP thread(s)" +
          (r.ranks > 1 ? " per rank, " + std::to_string(r.ranks) +
                             " MPI ranks (rank 0 scores and writes, the others inject)."
                       : std::string(".")),
      "Cement in every volume: minus the CT, " + r.thresholdRule +
          ", the component at the tip, as `cementsph compare` segments it."};
  if (!r.sizeRows.empty())
    preamble.push_back(
        "Reference: " + r.reference +
        ". Surface error: the paper's error, the larger of the two directed mean distances between the "
        "cement isosurfaces; spreading diff.: the run's mean spreading distance of its cement minus the "
        "reference's; Dice of the two cement masks. Wall time: the inject runner's, porous-solid set-up "
        "included.");
  preamble.push_back("Runs: " + fmt(runsWallTimeS(r), "%.1f") + " s (injections and cement analysis); study " +
                     fmt(r.studyWallTimeS, "%.1f") + " s in all so far.");
  return preamble;
}

} // namespace

std::vector<std::string> runSizeNotes(const StudyPlan& plan, double voxelVolumeMm3, bool allowLarge) {
  std::vector<StudyRunSpec> runs = plan.sizeStudy ? plan.sizeRuns() : std::vector<StudyRunSpec>{};
  for (const auto& run : plan.viscosityRuns()) runs.push_back(run);
  std::vector<std::string> notes;
  for (const auto& run : runs) {
    const std::string note =
        scene::checkRunSize(scene::estimateRun(run.scene(plan.baseScene), voxelVolumeMm3), allowLarge);
    if (!note.empty()) notes.push_back("run " + run.name() + ": " + note);
  }
  return notes;
}

std::string setReferenceCt(StudyRunner& runner, const imaging::ImageType* ct, const std::string& referenceCtPath,
                           bool registration, const std::string& thresholdRule) {
  const auto post = imaging::readVolume(referenceCtPath);
  const AlignedPost aligned = alignPostOntoPre(ct, post, registration);
  AnalysedCement cement = runner.analyse(aligned.volume);
  if (!cement.found())
    throw std::runtime_error(referenceCtPath + ": no cement found (reference minus CT " + thresholdRule +
                             ", at the tip)");
  const std::string description =
      "the post-operative CT `" + referenceCtPath + "`, " +
      (registration ? std::string("registered onto the CT as `compare` does (affine, cement masked)")
                    : std::string("resampled onto the CT without registration")) +
      "; its cement: " + fmt(cement.segmentation.volumeMl, "%.3f") + " ml, mean spreading distance " +
      fmt(cement.spreadingMm, "%.2f") + " mm";
  runner.setReference(std::move(cement));
  return description;
}

std::string finestRunReference(const StudyPlan& plan) {
  std::string reference;
  if (!plan.sizeStudy) return reference;
  for (const auto& run : plan.sizeRuns())
    if (run.reference)
      reference = "the finest run, " + run.integrator + " at r " + radiusLabel(run.particleRadiusMm) +
                  " mm (the smallest radius with the most faithful integrator listed: central-difference, "
                  "then explicit, then overdamped); it runs first";
  return reference;
}

double runsWallTimeS(const StudyRecord& record) {
  double sum = 0;
  for (const auto* rows : {&record.sizeRows, &record.viscosityRows})
    for (const auto& r : *rows) sum += r.wallTimeS + r.analysisTimeS;
  return sum;
}

json studyJson(const StudyRecord& r) {
  const StudyPlan& plan = *r.plan;
  json j;
  j["ct"] = r.ct;
  j["scene_file"] = r.sceneFile;
  j["scene"] = scene::toJson(plan.baseScene);
  j["radii_mm"] = plan.sizeStudy ? json(plan.radiiMm) : json::array();
  j["integrators"] = plan.sizeStudy ? json(plan.integrators) : json::array();
  j["viscosities_pa_s"] = plan.viscositiesPaS;
  j["reference"] = plan.sizeStudy ? json(r.reference) : json(nullptr);
  j["reference_ct"] = plan.referenceIsCt ? json(r.referenceCt) : json(nullptr);
  j["threads"] = r.threads;
  j["mpi_ranks"] = r.ranks;
  j["size_runs_done"] = r.sizeRows.size();
  j["viscosity_runs_done"] = r.viscosityRows.size();
  j["runs_wall_time_s"] = runsWallTimeS(r);
  j["study_wall_time_s"] = r.studyWallTimeS;
  j["provenance"] = provenance::toJson();
  return j;
}

std::vector<std::string> writeStudyTables(const StudyRecord& r, const fs::path& out) {
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw std::runtime_error(out.string() + ": cannot create the output folder: " + ec.message());
  std::vector<std::string> written{"study.md", "study.json"};
  if (!r.sizeRows.empty()) {
    imaging::writeTextAtomically((out / "study.csv").string(), sizeStudyCsv(r.sizeRows));
    written.push_back("study.csv");
  }
  if (!r.viscosityRows.empty()) {
    imaging::writeTextAtomically((out / "spreading_vs_viscosity.csv").string(), viscosityCsv(r.viscosityRows));
    written.push_back("spreading_vs_viscosity.csv");
  }
  imaging::writeTextAtomically((out / "study.md").string(), studyMarkdown(r.sizeRows, r.viscosityRows, studyPreamble(r)));
  imaging::writeTextAtomically((out / "study.json").string(), studyJson(r).dump(2) + "\n");
  return written;
}

} // namespace cementsph::study
