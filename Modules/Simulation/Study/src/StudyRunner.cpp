// ITK's transforms bring ITK's bundled Eigen Geometry, which does not compile after the system Eigen that
// SceneConfig.h (through StudyRunner.h) includes: ITK first.
#include "cementsph/imaging/AffineRegistration.h"

#include "cementsph/study/StudyRunner.h"

#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/parallel/CaseFarm.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/sph/Simulation.h"

#include "vtkSPHInjectionFilter.h"

#include <itkIdentityTransform.h>
#include <vtkImageData.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <stdexcept>

namespace cementsph::study {

void checkRunsCanStart(const imaging::ImageType* ct, const StudyPlan& plan) {
  scene::InjectionRunOptions check;
  check.checkOnly = true;
  for (const auto& runs : {plan.sizeRuns(), plan.viscosityRuns()})
    for (const StudyRunSpec& run : runs) scene::runInjection(ct, run.scene(plan.baseScene), check);
}

StudyRunner::StudyRunner(const imaging::ImageType* ct, StudyPlan plan, StudyOptions options)
    : ct_(ct), plan_(std::move(plan)), options_(std::move(options)) {
  if (ct_ == nullptr) throw std::invalid_argument("StudyRunner: no CT");
  ctImage_ = imaging::toVtk(ct_);
  const Eigen::Vector3d tip = *plan_.baseScene.tipMm;
  imaging::PointType p;
  for (unsigned a = 0; a < 3; ++a) p[a] = tip[int(a)];
  options_.segmentation.injectionPointMm = p;
}

void StudyRunner::setReference(AnalysedCement reference) { reference_ = std::move(reference); }

AnalysedCement StudyRunner::analyse(const imaging::ImageType* volume) const {
  imaging::ImageType::Pointer onGrid = const_cast<imaging::ImageType*>(volume);
  if (!imaging::geometryOf(volume).sameGrid(imaging::geometryOf(ct_))) {
    // The simulated CT covers the region of interest; outside it, air (below any cement threshold).
    auto identity = itk::IdentityTransform<double, 3>::New();
    onGrid = imaging::resampleOnto(volume, ct_, identity);
  }
  const Eigen::Vector3d tip = *plan_.baseScene.tipMm;
  return analyseCement(onGrid, ct_, options_.segmentation, {tip[0], tip[1], tip[2]}, options_.smoothingVoxels);
}

SimulatedRun StudyRunner::simulate(const StudyRunSpec& spec) const {
  // Through the injection filter, as `inject` runs it: its simulated CT lies on the CT's own grid (the CT's HU
  // outside the region of interest), so analyse() takes it as it is.
  auto filter = vtkSmartPointer<vtkSPHInjectionFilter>::New();
  filter->SetInputDataObject(0, ctImage_);
  filter->SetScene(spec.scene(plan_.baseScene));
  filter->SetHUPerRelativeDensity(options_.huPerRelativeDensity);
  if (!options_.keepRunsDir.empty())
    filter->SetOutputDirectory((std::filesystem::path(options_.keepRunsDir) / spec.name()).string());
  filter->Update();
  SimulatedRun simulated;
  try {
    filter->RethrowIfFailed();
  } catch (const sph::SimulationError& e) {
    simulated.failure = e.what();
    return simulated;
  }
  simulated.metrics = filter->GetResult()->metrics; // the typed result's, not its JSON text parsed back
  simulated.simulatedCt = imaging::imageFromVtk(filter->GetSimulatedCTOutput());
  return simulated;
}

StudyRow StudyRunner::score(const StudyRunSpec& spec, const SimulatedRun& simulated, int rank,
                            AnalysedCement* cement) const {
  StudyRow row;
  row.spec = spec;
  row.rank = rank;
  const scene::SceneConfig scene = spec.scene(plan_.baseScene);
  const double d = scene.spacingM();
  row.expectedParticles = scene.volumeM3() / (d * d * d);
  if (!simulated.failure.empty() || !simulated.simulatedCt) {
    row.failure = simulated.failure.empty() ? "no simulated CT" : simulated.failure;
    return row;
  }
  // The run's typed summary (the metrics crossed a process boundary as JSON under MPI).
  const scene::InjectionSummary m = scene::InjectionSummary::fromJson(simulated.metrics);
  row.wallTimeS = m.wallTimeS;
  row.realTimeFactor = m.wallTimeS > 0 ? m.simulatedTimeS / m.wallTimeS : 0.0;
  row.simulatedTimeS = m.simulatedTimeS;
  row.steps = m.steps;
  row.fluidParticles = m.cementPoints; // particles, or voxels holding cement
  row.fixedParticles = m.particles ? m.particles->fixed : 0;     // an engine without particles has none
  row.escapedParticles = m.particles ? m.particles->escaped : 0;
  row.volumeInjectedMl = m.volumeInjectedMl;
  row.particleSpreadingMm = m.meanSpreadingDistanceMm;
  row.maxTipPressurePa = m.maxTipPressurePa;
  row.finalTipPressurePa = m.finalTipPressurePa;
  row.fluidInSolidFraction = m.fluidInSolidFraction;

  const auto start = std::chrono::steady_clock::now();
  AnalysedCement c = analyse(simulated.simulatedCt);
  row.cementFound = c.found();
  row.cementVolumeMl = c.segmentation.volumeMl;
  row.cementSpreadingMm = c.spreadingMm;
  // The reference run is scored against itself (all zero, Dice 1), every other against the reference.
  if (spec.reference) row.errors = cementErrors(c, c);
  else if (reference_ && spec.sweep == StudyRunSpec::Sweep::ParticleSize) row.errors = cementErrors(c, *reference_);
  row.analysisTimeS = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (cement) *cement = std::move(c);
  return row;
}

StudyRow StudyRunner::run(const StudyRunSpec& spec, AnalysedCement* cement) const {
  return score(spec, simulate(spec), 0, cement);
}

std::vector<StudyRow> StudyRunner::runCases(const std::vector<StudyRunSpec>& specs, parallel::CaseFarm* farm,
                                            const RowCallback& afterEachRun, const StartCallback& beforeEachRun) {
  const bool sizeRuns = std::any_of(specs.begin(), specs.end(), [](const StudyRunSpec& s) {
    return s.sweep == StudyRunSpec::Sweep::ParticleSize;
  });
  if (sizeRuns && plan_.referenceIsCt && !reference_)
    throw std::logic_error("StudyRunner: the plan's reference is a CT, but none was set");
  std::vector<StudyRow> rows;
  // The reference run comes first in the plan, so it is scored (and becomes the reference) before any run
  // that is scored against it.
  auto onOutcome = [&](const parallel::CaseOutcome& outcome) {
    const StudyRunSpec& spec = specs[outcome.index];
    if (!outcome.ok) {
      SimulatedRun failed;
      failed.failure = (farm && farm->ranks() > 1 ? "rank " + std::to_string(outcome.rank) + ": " : std::string()) +
                       outcome.payload;
      rows.push_back(score(spec, failed, outcome.rank));
    } else if (spec.reference) {
      AnalysedCement cement;
      rows.push_back(score(spec, decodeSimulatedRun(outcome.payload), outcome.rank, &cement));
      if (rows.back().ok()) reference_ = std::move(cement);
    } else {
      rows.push_back(score(spec, decodeSimulatedRun(outcome.payload), outcome.rank));
    }
    if (afterEachRun) afterEachRun(rows, specs.size());
  };
  auto work = [&](std::size_t i) {
    if (beforeEachRun) beforeEachRun(specs[i], i, specs.size());
    return encodeSimulatedRun(simulate(specs[i]));
  };
  if (farm) farm->run(specs.size(), work, onOutcome);
  else parallel::runCasesHere(specs.size(), work, onOutcome);
  return rows;
}

std::vector<StudyRow> StudyRunner::runSizeStudy(const RowCallback& afterEachRun) {
  return runCases(plan_.sizeRuns(), nullptr, afterEachRun);
}

std::vector<StudyRow> StudyRunner::runViscositySweep(const RowCallback& afterEachRun) {
  return runCases(plan_.viscosityRuns(), nullptr, afterEachRun);
}

std::vector<StudyRow> StudyRunner::runStudy(parallel::CaseFarm& farm, const RowCallback& afterEachRun,
                                            const StartCallback& beforeEachRun) {
  std::vector<StudyRunSpec> specs = plan_.sizeStudy ? plan_.sizeRuns() : std::vector<StudyRunSpec>{};
  for (const StudyRunSpec& spec : plan_.viscosityRuns()) specs.push_back(spec);
  return runCases(specs, &farm, afterEachRun, beforeEachRun);
}

} // namespace cementsph::study
