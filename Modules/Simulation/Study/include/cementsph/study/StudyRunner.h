// Runs a StudyPlan on one CT: each run is an injection by the inject runner (InjectionRunner.h) with the
// run's scene; its simulated CT is put on the CT's grid and its cement segmented and measured exactly as
// `cementsph compare` does (AnalysedCement: post minus pre above 500 HU, the component at the tip, the
// isosurface after a 1-voxel Gaussian); then scored against the reference (CementErrors), which is either
// the size study's finest run (StudyPlan) or a post-operative CT's cement set with setReference().
// The paper's Fig. 6 scores particle sizes the same way: surface error of the simulated cement against
// the reference one.
//
// A run whose engine goes unstable (sph::SimulationError) is kept as a failed row and the study goes on;
// any other error (bad scene, tip in solid, output failure) is thrown.
#pragma once

#include "cementsph/imaging/CementSegmentation.h"
#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/study/AnalysedCement.h"
#include "cementsph/study/StudyPlan.h"
#include "cementsph/study/StudyRow.h"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace cementsph::study {

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

  // The plan must be validated; ct must outlive the runner.
  StudyRunner(const imaging::ImageType* ct, StudyPlan plan, StudyOptions options = {});

  // A post-operative CT's cement (on the CT's grid) as the size study's reference (plan.referenceIsCt).
  void setReference(AnalysedCement reference);
  // The reference cement once known (after setReference, or after the reference run); null before.
  const AnalysedCement* reference() const { return reference_ ? &*reference_ : nullptr; }

  std::vector<StudyRow> runSizeStudy(const RowCallback& afterEachRun = {});
  std::vector<StudyRow> runViscositySweep(const RowCallback& afterEachRun = {});

  // One run, measured; its cement is handed back in `cement` when given.
  StudyRow run(const StudyRunSpec& spec, AnalysedCement* cement = nullptr) const;

  // The CT's cement analysis of any volume on (or resampled onto) the CT's grid.
  AnalysedCement analyse(const imaging::ImageType* volume) const;

  const StudyPlan& plan() const { return plan_; }

private:
  const imaging::ImageType* ct_;
  StudyPlan plan_;
  StudyOptions options_;
  std::optional<AnalysedCement> reference_;
};

} // namespace cementsph::study
