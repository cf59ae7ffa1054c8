// ITK's transforms bring ITK's bundled Eigen Geometry, which does not compile after the system Eigen that
// SceneConfig.h (through StudyRunner.h) includes: ITK first.
#include "cementsph/imaging/AffineRegistration.h"

#include "cementsph/study/StudyRunner.h"

#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/sph/Simulation.h"

#include <itkIdentityTransform.h>

#include <chrono>
#include <filesystem>
#include <stdexcept>

namespace cementsph::study {

StudyRunner::StudyRunner(const imaging::ImageType* ct, StudyPlan plan, StudyOptions options)
    : ct_(ct), plan_(std::move(plan)), options_(std::move(options)) {
  if (ct_ == nullptr) throw std::invalid_argument("StudyRunner: no CT");
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

StudyRow StudyRunner::run(const StudyRunSpec& spec, AnalysedCement* cement) const {
  StudyRow row;
  row.spec = spec;
  const scene::SceneConfig scene = spec.scene(plan_.baseScene);
  const double d = scene.spacingM();
  row.expectedParticles = scene.volumeM3() / (d * d * d);

  scene::InjectionRunOptions runOptions;
  runOptions.huPerRelativeDensity = options_.huPerRelativeDensity;
  if (!options_.keepRunsDir.empty())
    runOptions.outDir = (std::filesystem::path(options_.keepRunsDir) / spec.name()).string();
  scene::InjectionRunResult result;
  try {
    result = scene::runInjection(ct_, scene, runOptions);
  } catch (const sph::SimulationError& e) {
    row.failure = e.what();
    return row;
  }
  const auto& m = result.metrics;
  row.wallTimeS = m.at("wall_time_s").get<double>();
  row.realTimeFactor = m.at("real_time_factor").get<double>();
  row.simulatedTimeS = m.at("simulated_time_s").get<double>();
  row.steps = m.at("steps").get<std::size_t>();
  row.fluidParticles = m.at("fluid_particles").get<std::size_t>();
  row.fixedParticles = m.at("fixed_particles").get<std::size_t>();
  row.escapedParticles = m.at("escaped_particles").get<std::size_t>();
  row.volumeInjectedMl = m.at("volume_injected_ml").get<double>();
  row.particleSpreadingMm = m.at("mean_spreading_distance_mm").get<double>();
  row.maxTipPressurePa = m.at("max_tip_pressure_pa").get<double>();
  row.fluidInSolidFraction = m.at("fluid_in_solid_fraction").get<double>();

  const auto start = std::chrono::steady_clock::now();
  AnalysedCement c = analyse(result.simulatedCt);
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

std::vector<StudyRow> StudyRunner::runSizeStudy(const RowCallback& afterEachRun) {
  if (plan_.referenceIsCt && !reference_)
    throw std::logic_error("StudyRunner: the plan's reference is a CT, but none was set");
  const std::vector<StudyRunSpec> specs = plan_.sizeRuns();
  std::vector<StudyRow> rows;
  for (const StudyRunSpec& spec : specs) {
    if (spec.reference) {
      AnalysedCement cement;
      rows.push_back(run(spec, &cement));
      if (rows.back().ok()) reference_ = std::move(cement);
    } else {
      rows.push_back(run(spec));
    }
    if (afterEachRun) afterEachRun(rows, specs.size());
  }
  return rows;
}

std::vector<StudyRow> StudyRunner::runViscositySweep(const RowCallback& afterEachRun) {
  const std::vector<StudyRunSpec> specs = plan_.viscosityRuns();
  std::vector<StudyRow> rows;
  for (const StudyRunSpec& spec : specs) {
    rows.push_back(run(spec));
    if (afterEachRun) afterEachRun(rows, specs.size());
  }
  return rows;
}

} // namespace cementsph::study
