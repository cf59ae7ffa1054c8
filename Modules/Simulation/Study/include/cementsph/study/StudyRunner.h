// Runs a StudyPlan on one CT: each run is an injection by the injection filter (vtkSPHInjectionFilter, the
// inject runner of InjectionRunner.h as a VTK algorithm, as `inject` runs it) with the run's scene; its
// simulated CT (the filter's output 0, on the CT's own grid) has its cement segmented and measured exactly as
// `cementsph compare` does (AnalysedCement: post minus pre above 500 HU, the component at the tip, the
// isosurface after a 1-voxel Gaussian); then scored against the reference (CementErrors), which is either
// the size study's finest run (StudyPlan) or a post-operative CT's cement set with setReference().
// The paper's Fig. 6 scores particle sizes the same way: surface error of the simulated cement against
// the reference one.
//
// A run whose engine goes unstable (sph::SimulationError) is kept as a failed row and the study goes on;
// so is a run that failed for any other reason but bad input (its failure says why). Bad input (a bad
// scene, a tip in solid: std::invalid_argument) stops the study and is thrown; checkRunsCanStart finds it
// before the first run starts.
//
// The runs may be spread over the ranks of an MPI job (parallel::CaseFarm): each injection runs on a worker
// rank, which sends back its metrics and simulated CT (SimulatedRun, encoded as bytes); rank 0 segments,
// measures and scores every run in plan order, so the rows are the same as a serial study's, number for
// number (the wall times and the rank column aside).
#pragma once

#include "cementsph/imaging/CementSegmentation.h"
#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/study/AnalysedCement.h"
#include "cementsph/study/StudyPlan.h"
#include "cementsph/study/StudyRow.h"

#include <nlohmann/json.hpp>
#include <vtkSmartPointer.h>

#include <functional>
#include <optional>
#include <string>
#include <vector>

class vtkImageData;

namespace cementsph::parallel {
class CaseFarm;
}

namespace cementsph::study {

// One injection of a study before its cement is analysed: what a worker rank sends back.
struct SimulatedRun {
  std::string failure;                      // the engine went unstable (empty: it finished)
  nlohmann::json metrics;                   // the inject runner's metrics.json
  imaging::ImageType::Pointer simulatedCt;  // null when it failed
};
// Bytes and back: the metrics as JSON (doubles read back to the same bits), the image's geometry and its
// voxels as they are. decode throws std::runtime_error for bytes that are not an encoded run.
std::string encodeSimulatedRun(const SimulatedRun& run);
SimulatedRun decodeSimulatedRun(const std::string& bytes);

// Every check each run of the plan makes before its first step (its scene; the tip outside the CT, in solid or
// without the pore space to inject into; the engine's own start checks), all runs before any starts: throws
// the first run's std::invalid_argument, as that run would. The plan must be validated.
void checkRunsCanStart(const imaging::ImageType* ct, const StudyPlan& plan);

struct StudyOptions {
  // Segmentation of every cement (the injection point is set to the scene's tip).
  imaging::SegmentationOptions segmentation;
  double smoothingVoxels = 1.0;           // IsosurfaceOptions::smoothingSigmaVoxels, as compare's default
  double huPerRelativeDensity = 3000.0;   // k of the simulated CT (InjectionRunOptions)
  std::string keepRunsDir;                // empty: runs write no files; else each run's inject outputs in
                                          // keepRunsDir/<StudyRunSpec::name()>
};

class StudyRunner {
public:
  // Called after every run with the rows so far and the number of runs planned.
  using RowCallback = std::function<void(const std::vector<StudyRow>& rows, std::size_t planned)>;
  // Called as a run starts, in the process that runs it (a worker rank under MPI), with the run, its index
  // in the list of cases (runStudy: the size study's runs, then the sweep's) and the number of cases.
  using StartCallback = std::function<void(const StudyRunSpec& run, std::size_t index, std::size_t planned)>;

  // The plan must be validated; ct must outlive the runner.
  StudyRunner(const imaging::ImageType* ct, StudyPlan plan, StudyOptions options = {});

  // A post-operative CT's cement (on the CT's grid) as the size study's reference (plan.referenceIsCt).
  void setReference(AnalysedCement reference);
  // The reference cement once known (after setReference, or after the reference run); null before.
  const AnalysedCement* reference() const { return reference_ ? &*reference_ : nullptr; }

  std::vector<StudyRow> runSizeStudy(const RowCallback& afterEachRun = {});
  std::vector<StudyRow> runViscositySweep(const RowCallback& afterEachRun = {});
  // Both, the size study's runs first, as one list of cases over the farm's ranks (every rank calls it).
  // On rank 0: every row, in plan order, each to afterEachRun as it is scored; on a worker: nothing.
  std::vector<StudyRow> runStudy(parallel::CaseFarm& farm, const RowCallback& afterEachRun = {},
                                 const StartCallback& beforeEachRun = {});

  // One run, measured; its cement is handed back in `cement` when given.
  StudyRow run(const StudyRunSpec& spec, AnalysedCement* cement = nullptr) const;
  // The two halves of run(): the injection (on any rank), then the cement's analysis and scores against
  // the reference (rank 0). `rank` is recorded in the row.
  SimulatedRun simulate(const StudyRunSpec& spec) const;
  StudyRow score(const StudyRunSpec& spec, const SimulatedRun& simulated, int rank = 0,
                 AnalysedCement* cement = nullptr) const;

  // The CT's cement analysis of any volume on (or resampled onto) the CT's grid.
  AnalysedCement analyse(const imaging::ImageType* volume) const;

  const StudyPlan& plan() const { return plan_; }

private:
  std::vector<StudyRow> runCases(const std::vector<StudyRunSpec>& specs, parallel::CaseFarm* farm,
                                 const RowCallback& afterEachRun, const StartCallback& beforeEachRun = {});

  const imaging::ImageType* ct_;
  vtkSmartPointer<vtkImageData> ctImage_; // ct_ as the injection filter's input, converted once
  StudyPlan plan_;
  StudyOptions options_;
  std::optional<AnalysedCement> reference_;
};

} // namespace cementsph::study
