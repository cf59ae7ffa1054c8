// cementsph study: the paper's particle-size study (Basafa et al. 2013, Fig. 6) as the speed-against-error
// report the user asked for, and its viscosity sweep (Fig. 8). Every radius with every integrator is an
// injection of the scene into the CT (the inject runner); each simulated CT's cement is segmented as
// `compare` does and scored against the reference: the finest run (smallest radius, most faithful
// integrator) or a post-operative CT. Writes DIR/study.csv (rewritten after every run, so an interrupted
// study keeps what it finished), study.md, study.json, error_vs_wall_time.png and, with --viscosities-pa-s,
// spreading_vs_viscosity.csv and .png (Fig. 8) and end_pressure_vs_viscosity.png (Fig. 9, simulated half). A thin layer over CementSPH::Study (Modules/Simulation/Study).
// A thin layer: the reference, the run-size notes and the tables' schemas are CementSPH::Study's
// (StudyOutputs.h); this file parses the options, runs the plan and prints the progress and summary.
// AlignedPost.h (ITK transforms, with ITK's bundled Eigen Geometry) must come before the system Eigen of
// SceneConfig.h.
#include "cementsph/study/AlignedPost.h"

#include "CommandRegistry.h"
#include "OutputFiles.h"
#include "SceneOverrides.h"

#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/parallel/CaseFarm.h"
#include "cementsph/scene/RunEstimate.h"
#include "cementsph/scene/SceneConfig.h"
#include "cementsph/study/StudyOutputs.h"
#include "cementsph/study/StudyPlots.h"
#include "cementsph/study/StudyReport.h"
#include "cementsph/study/StudyRunner.h"

#include <omp.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

namespace {

namespace fs = std::filesystem;
using namespace cementsph;

struct StudyArgs {
  std::string ct, scene, out, referenceCt;
  app::SceneOverrideArgs scene_overrides;
  std::vector<double> radiiMm{1.00, 0.75, 0.57, 0.50, 0.45};
  std::vector<std::string> integrators{"overdamped", "central-difference"};
  std::vector<double> viscositiesPaS;
  bool noSizeStudy = false, noRegistration = false, keepRuns = false, noPictures = false;
  int threads = 0;
  bool allowLarge = false;
};

std::string fmt(double x, const char* format = "%.3g") {
  char buf[48];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

// "size 2/4: overdamped r 1.00 mm", "viscosity 1/2: overdamped r 0.57 mm, 100 Pa.s", "... (reference)".
std::string runLabel(const study::StudyRunSpec& spec, std::size_t index, std::size_t planned) {
  std::ostringstream line;
  const bool size = spec.sweep == study::StudyRunSpec::Sweep::ParticleSize;
  line << (size ? "size " : "viscosity ") << index << "/" << planned << ": " << spec.integrator << " r "
       << study::radiusLabel(spec.particleRadiusMm) << " mm";
  if (!size) line << ", " << spec.viscosityPaS << " Pa.s";
  if (spec.reference) line << " (reference)";
  return line.str();
}

std::string progressLine(const study::StudyRow& r, std::size_t index, std::size_t planned) {
  std::ostringstream line;
  line << "study " << runLabel(r.spec, index, planned);
  if (!r.ok()) return line.str() + ": failed: " + r.failure;
  line << ": " << r.fluidParticles << " fluid + " << r.fixedParticles << " fixed particles, " << r.steps
       << " steps, " << fmt(r.wallTimeS) << " s wall (real-time factor " << fmt(r.realTimeFactor) << ")";
  if (r.spec.sweep == study::StudyRunSpec::Sweep::Viscosity)
    line << "; spreading " << fmt(r.particleSpreadingMm, "%.2f") << " mm (particles), "
         << (r.cementFound ? fmt(r.cementSpreadingMm, "%.2f") + " mm (simulated CT)" : "no cement in the simulated CT");
  else if (r.errors.surfaceErrorMm)
    line << "; surface error " << fmt(*r.errors.surfaceErrorMm, "%.3f") << " mm, spreading diff "
         << fmt(*r.errors.spreadingDifferenceMm, "%+.3f") << " mm, Dice " << fmt(*r.errors.dice, "%.3f");
  else if (!r.cementFound)
    line << "; no cement in the simulated CT";
  return line.str();
}

// What the study needs before its runs.
struct StudySession {
  study::StudyPlan plan;
  imaging::ImageType::Pointer ct;
  std::unique_ptr<study::StudyRunner> runner;
  study::StudyOptions options;
  std::string reference; // study.md's description of the size study's reference
};

// Under mpirun the ranks share the injections: each gets its share of the cores unless told otherwise.
void setThreads(const StudyArgs& a, const parallel::CaseFarm& farm) {
  if (a.threads > 0) omp_set_num_threads(a.threads);
  else if (farm.ranks() > 1 && !std::getenv("OMP_NUM_THREADS"))
    omp_set_num_threads(farm.threadsPerRank(omp_get_num_procs()));
}

void checkArgs(const StudyArgs& a) {
  if (a.threads < 0) throw std::invalid_argument("--threads: " + std::to_string(a.threads) + " is negative");
  if (a.noRegistration && a.referenceCt.empty()) throw std::invalid_argument("--no-registration needs --reference-ct");
  if (!a.referenceCt.empty() && a.noSizeStudy)
    throw std::invalid_argument("--reference-ct scores the size study, but --no-size-study turns it off");
  // Each radius, integrator and viscosity is a full injection: a sweep of 1e5 viscosities spent minutes in
  // the start checks alone. The paper's figures use 5 radii and 4 viscosities.
  constexpr std::size_t kMaxSweep = 100;
  for (const auto& [option, count] : {std::pair<const char*, std::size_t>{"--radii-mm", a.radiiMm.size()},
                                      {"--integrators", a.integrators.size()},
                                      {"--viscosities-pa-s", a.viscositiesPaS.size()}})
    if (count > kMaxSweep)
      throw std::invalid_argument(std::string(option) + ": " + std::to_string(count) + " values; at most " +
                                  std::to_string(kMaxSweep) + " (each is a full injection)");
}

// Each radius of the size study against the scene keys it must fit (SceneConfig::validate's, for particle_radius_mm):
// the line names --radii-mm, which set the radius, not the scene's cannula key ("key 'cannula_inner_diameter_mm'
// must be at least one particle diameter" for `--radii-mm 16`).
void checkRadiiFitTheScene(const StudyArgs& a, const scene::SceneConfig& base) {
  if (a.noSizeStudy) return;
  for (const double r : a.radiiMm) {
    if (2 * r > base.cannulaInnerDiameterMm)
      throw std::invalid_argument("--radii-mm " + app::exactNumber(r) + ": a particle " + app::exactNumber(2 * r) +
                                  " mm across does not fit the cannula (cannula_inner_diameter_mm " +
                                  app::exactNumber(base.cannulaInnerDiameterMm) + "): give radii up to " +
                                  app::exactNumber(base.cannulaInnerDiameterMm / 2) + " mm");
    if (8 * r > base.roiSizeMm)
      throw std::invalid_argument("--radii-mm " + app::exactNumber(r) + ": the region (roi_size_mm " +
                                  app::exactNumber(base.roiSizeMm) + ") must be at least 4 particle diameters: give radii up to " +
                                  app::exactNumber(base.roiSizeMm / 8) + " mm");
  }
}

// Everything that can be checked before a run: options, scene, output folder, CT, reference.
void prepare(const StudyArgs& a, const CLI::App& sub, const parallel::CaseFarm& farm, StudySession& s) {
  checkArgs(a);
  s.plan.baseScene = scene::loadSceneFile(a.scene, app::sceneSettings(sub, a.scene_overrides));
  s.plan.sizeStudy = !a.noSizeStudy;
  s.plan.radiiMm = a.radiiMm;
  s.plan.integrators = a.integrators;
  s.plan.viscositiesPaS = a.viscositiesPaS;
  s.plan.referenceIsCt = !a.referenceCt.empty();
  checkRadiiFitTheScene(a, s.plan.baseScene); // before the plan's own check, which names the scene key
  s.plan.validate();
  app::checkOutputFolder(a.out);
  s.ct = imaging::readVolume(a.ct);
  // Every run's tip and start checks before the first run (a tip in solid is one line at once, not after a
  // run); rank 0's check speaks for all ranks (they run the same plan on the same CT).
  if (farm.coordinator()) study::checkRunsCanStart(s.ct, s.plan);
  const auto spacing = s.ct->GetSpacing();
  for (const std::string& note : study::runSizeNotes(s.plan, spacing[0] * spacing[1] * spacing[2], a.allowLarge))
    if (farm.coordinator()) std::cerr << "cementsph study: " << note << "\n";
  if (a.keepRuns) s.options.keepRunsDir = (fs::path(a.out) / "runs").string();
  s.runner = std::make_unique<study::StudyRunner>(s.ct, s.plan, s.options);
  // The reference is scored on rank 0 only: the workers need not read or register it.
  if (s.plan.referenceIsCt && farm.coordinator())
    s.reference = study::setReferenceCt(*s.runner, s.ct, a.referenceCt, !a.noRegistration,
                                        imaging::describeThresholdRule(s.options.segmentation));
  else if (s.plan.sizeStudy)
    s.reference = study::finestRunReference(s.plan);
}

// 3. Pictures, after the tables, so a rendering failure never loses the numbers (exit 3, as compare).
std::vector<std::string> drawPictures(const StudyArgs& a, const study::StudyRecord& record, app::PictureSteps& pictures) {
  const fs::path out(a.out);
  if (!a.noPictures && !record.sizeRows.empty())
    pictures.draw("error_vs_wall_time.png", out / "error_vs_wall_time.png",
                  [&](const fs::path& png) { study::writeErrorVsWallTimePlot(record.sizeRows, png); });
  if (!a.noPictures && !record.viscosityRows.empty())
    pictures.draw("spreading_vs_viscosity.png", out / "spreading_vs_viscosity.png",
                  [&](const fs::path& png) { study::writeSpreadingVsViscosityPlot(record.viscosityRows, png); });
  if (!a.noPictures && !record.viscosityRows.empty())
    pictures.draw("end_pressure_vs_viscosity.png", out / "end_pressure_vs_viscosity.png",
                  [&](const fs::path& png) { study::writeEndPressureVsViscosityPlot(record.viscosityRows, png); });
  return pictures.written();
}

int runStudy(const StudyArgs& a, const CLI::App& sub) {
  const auto start = std::chrono::steady_clock::now();
  auto seconds = [&start] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  // Under mpirun the ranks share the injections (Modules/Parallel/CaseFarm): every rank reads and checks
  // the inputs, rank 0 alone scores the runs and writes; without mpirun this process runs them all.
  parallel::CaseFarm& farm = parallel::caseFarm();
  setThreads(a, farm);
  StudySession session;
  farm.agree([&] { prepare(a, sub, farm, session); });
  const std::size_t sizePlanned = session.plan.sizeStudy ? session.plan.sizeRuns().size() : 0;
  const std::size_t viscosityPlanned = session.plan.viscosityRuns().size();
  // A line as each run starts, from the process that runs it (a worker rank under mpirun), so a long study
  // shows it is working before its first result. Through std::cerr's buffer but not std::cerr itself: a
  // worker's std::cerr is kept silent for errors (rank 0 reports those), --quiet swaps the buffer out.
  auto announce = [&](const study::StudyRunSpec& spec, std::size_t index, std::size_t) {
    const bool size = index < sizePlanned;
    std::ostream line(std::cerr.rdbuf());
    line << "study starting " << runLabel(spec, size ? index + 1 : index - sizePlanned + 1,
                                          size ? sizePlanned : viscosityPlanned)
         << (farm.ranks() > 1 ? " [rank " + std::to_string(farm.rank()) + "]" : std::string()) << std::endl;
  };
  if (!farm.coordinator()) { // a worker: injections only
    session.runner->runStudy(farm, {}, announce);
    return 0;
  }

  // 2. The runs: a line as each starts (announce) and, after each, every table rewritten (atomically) and one
  // progress line with its figures.
  study::StudyRecord record{a.ct, a.scene, a.referenceCt, &session.plan, session.reference,
                            imaging::describeThresholdRule(session.options.segmentation), omp_get_max_threads(),
                            farm.ranks(), {}, {}, 0.0};
  std::vector<std::string> written;
  auto writeTables = [&] {
    record.studyWallTimeS = seconds();
    written = study::writeStudyTables(record, a.out);
  };
  int status = 0;
  session.runner->runStudy(farm, [&](const std::vector<study::StudyRow>& rows, std::size_t) {
    const study::StudyRow& last = rows.back();
    const bool size = last.spec.sweep == study::StudyRunSpec::Sweep::ParticleSize;
    auto& into = size ? record.sizeRows : record.viscosityRows;
    into.push_back(last);
    if (!last.ok()) status = 3;
    writeTables();
    std::cerr << progressLine(last, into.size(), size ? sizePlanned : viscosityPlanned)
              << (farm.ranks() > 1 ? " [rank " + std::to_string(last.rank) + "]" : std::string()) << std::endl;
  }, announce);
  writeTables();

  app::PictureSteps pictures("study", "the tables");
  for (const std::string& name : drawPictures(a, record, pictures)) written.push_back(name);
  if (pictures.status() != 0) status = 3;
  std::cout << "study done: " << record.sizeRows.size() + record.viscosityRows.size() << " runs, "
            << fmt(seconds(), "%.1f") << " s wall; wrote";
  for (const auto& name : written) std::cout << " " << (fs::path(a.out) / name).string();
  std::cout << "\n";
  if (status == 3) std::cerr << "cementsph study: some runs failed or pictures are missing (exit status 3)\n";
  return status;
}

cementsph::app::CommandRunner setupStudy(CLI::App& sub) {
  auto a = std::make_shared<StudyArgs>();
  sub.add_option("--ct", a->ct, "CT volume in HU (file: .nrrd .mha .nii .nii.gz, or a DICOM directory)")->required();
  sub.add_option("--scene", a->scene, "Scene file (JSON; keys name their units, see docs/scene-figures.md)")
      ->required();
  sub.add_option("--out", a->out, "Output folder (created; existing files are replaced)")->required();
  sub.add_option("--radii-mm", a->radiiMm, "Particle radii of the size study, mm (paper Fig. 6)")
      ->delimiter(',')
      ->capture_default_str();
  sub.add_option("--integrators", a->integrators,
                 "Integrators of the size study (overdamped, central-difference, explicit)")
      ->delimiter(',')
      ->capture_default_str();
  sub.add_flag("--no-size-study", a->noSizeStudy, "Run only the viscosity sweep");
  sub.add_option("--viscosities-pa-s", a->viscositiesPaS,
                 "Also sweep these viscosities, Pa.s, at the scene's radius and integrator (paper Figs. 8, 9): "
                 "spreading_vs_viscosity.csv and .png, end_pressure_vs_viscosity.png")
      ->delimiter(',');
  sub.add_option("--reference-ct", a->referenceCt,
                 "Score against this post-operative CT (registered onto --ct as compare does) instead of the "
                 "finest run");
  sub.add_flag("--no-registration", a->noRegistration,
               "The reference CT is already aligned with --ct (it is only resampled onto its grid)");
  app::addSceneOverrideOptions(sub, a->scene_overrides);
  sub.add_option("--threads", a->threads, "OpenMP threads (0: the cores the load average leaves free)");
  sub.add_flag("--keep-runs", a->keepRuns, "Keep every run's inject outputs in DIR/runs/<integrator>_r<radius>mm");
  sub.add_flag("--no-pictures", a->noPictures, "Do not write the PNG plots");
  sub.add_flag("--allow-large", a->allowLarge, "Run even when a run's estimated work is hours (see inject --allow-large)");

  return [a, &sub]() { return runStudy(*a, sub); };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND_OVER_RANKS(study_command, "study",
                           "Particle-size study (paper Fig. 6) as speed against error: radii x integrators, wall "
                           "time, particles, error against the finest run or a post-operative CT; viscosity sweep "
                           "(Fig. 8)",
                           setupStudy)
