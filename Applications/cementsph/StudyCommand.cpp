// cementsph study: the paper's particle-size study (Basafa et al. 2013, Fig. 6) as the speed-against-error
// report the user asked for, and its viscosity sweep (Fig. 8). Every radius with every integrator is an
// injection of the scene into the CT (the inject runner); each simulated CT's cement is segmented as
// `compare` does and scored against the reference: the finest run (smallest radius, most faithful
// integrator) or a post-operative CT. Writes DIR/study.csv (rewritten after every run, so an interrupted
// study keeps what it finished), study.md, study.json, error_vs_wall_time.png and, with --viscosities-pa-s,
// spreading_vs_viscosity.csv and .png. A thin layer over CementSPH::Study (Modules/Simulation/Study).
// AlignedPost.h (ITK transforms, with ITK's bundled Eigen Geometry) must come before the system Eigen of
// SceneConfig.h.
#include "cementsph/provenance/Provenance.h"
#include "cementsph/study/AlignedPost.h"

#include "CommandRegistry.h"
#include "SceneOverrides.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/parallel/CaseFarm.h"
#include "cementsph/scene/RunEstimate.h"
#include "cementsph/scene/SceneConfig.h"
#include "cementsph/study/StudyPlots.h"
#include "cementsph/study/StudyReport.h"
#include "cementsph/study/StudyRunner.h"

#include <nlohmann/json.hpp>

#include <omp.h>
#include <unistd.h>

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
using nlohmann::json;

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

// Refuses, before anything runs, an output path that is a file or lies under a folder we cannot write.
void checkOutputFolder(const fs::path& out) {
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw std::runtime_error(out.string() + ": exists and is not a folder");
  fs::path p = fs::absolute(out, ec);
  while (!p.empty() && !fs::exists(p, ec) && p != p.parent_path()) p = p.parent_path();
  if (access(p.c_str(), W_OK) != 0) throw std::runtime_error(out.string() + ": cannot write in " + p.string());
}

std::string fmt(double x, const char* format = "%.3g") {
  char buf[48];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

std::string progressLine(const study::StudyRow& r, std::size_t index, std::size_t planned, const char* what) {
  std::ostringstream line;
  line << "study " << what << " " << index << "/" << planned << ": " << r.spec.integrator << " r "
       << study::radiusLabel(r.spec.particleRadiusMm) << " mm";
  if (r.spec.sweep == study::StudyRunSpec::Sweep::Viscosity) line << ", " << r.spec.viscosityPaS << " Pa.s";
  if (r.spec.reference) line << " (reference)";
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
                 "Also sweep these viscosities, Pa.s, at the scene's radius and integrator (paper Fig. 8): "
                 "spreading_vs_viscosity.csv and .png")
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

  return [a, &sub]() {
    const auto start = std::chrono::steady_clock::now();
    // Under mpirun the ranks share the injections (Modules/Parallel/CaseFarm): every rank reads and checks
    // the inputs, rank 0 alone scores the runs and writes; without mpirun this process runs them all.
    parallel::CaseFarm& farm = parallel::caseFarm();
    if (a->threads > 0) omp_set_num_threads(a->threads);
    else if (farm.ranks() > 1 && !std::getenv("OMP_NUM_THREADS"))
      omp_set_num_threads(farm.threadsPerRank(omp_get_num_procs()));
    study::StudyPlan plan;
    const fs::path out(a->out);
    imaging::ImageType::Pointer ct;
    std::unique_ptr<study::StudyRunner> runner;
    study::StudyOptions options;
    std::string reference;
    // 1. Everything that can be checked before a run: options, scene, output folder, CT, reference.
    farm.agree([&] {
      if (a->threads < 0) throw std::invalid_argument("--threads: " + std::to_string(a->threads) + " is negative");
      if (a->noRegistration && a->referenceCt.empty())
        throw std::invalid_argument("--no-registration needs --reference-ct");
      if (!a->referenceCt.empty() && a->noSizeStudy)
        throw std::invalid_argument("--reference-ct scores the size study, but --no-size-study turns it off");
      plan.baseScene = scene::loadSceneFile(a->scene, app::sceneOverrides(sub, a->scene_overrides));
      plan.sizeStudy = !a->noSizeStudy;
      plan.radiiMm = a->radiiMm;
      plan.integrators = a->integrators;
      plan.viscositiesPaS = a->viscositiesPaS;
      plan.referenceIsCt = !a->referenceCt.empty();
      plan.validate();
      checkOutputFolder(out);
      ct = imaging::readVolume(a->ct);
      {
        const auto spacing = ct->GetSpacing();
        std::vector<study::StudyRunSpec> runs = plan.sizeStudy ? plan.sizeRuns() : std::vector<study::StudyRunSpec>{};
        for (const auto& run : plan.viscosityRuns()) runs.push_back(run);
        for (const auto& run : runs) {
          const std::string note = scene::checkRunSize(
              scene::estimateRun(run.scene(plan.baseScene), spacing[0] * spacing[1] * spacing[2]), a->allowLarge);
          if (!note.empty() && farm.coordinator())
            std::cerr << "cementsph study: run " << run.name() << ": " << note << "\n";
        }
      }
      if (a->keepRuns) options.keepRunsDir = (out / "runs").string();
      runner = std::make_unique<study::StudyRunner>(ct, plan, options);
      // The reference is scored on rank 0 only: the workers need not read or register it.
      if (plan.referenceIsCt && farm.coordinator()) {
        const auto post = imaging::readVolume(a->referenceCt);
        const study::AlignedPost aligned = study::alignPostOntoPre(ct, post, !a->noRegistration);
        study::AnalysedCement cement = runner->analyse(aligned.volume);
        if (!cement.found())
          throw std::runtime_error(a->referenceCt + ": no cement found (reference minus CT " +
                                   imaging::describeThresholdRule(options.segmentation) + ", at the tip)");
        reference = "the post-operative CT `" + a->referenceCt + "`, " +
                    (a->noRegistration ? std::string("resampled onto the CT without registration")
                                       : std::string("registered onto the CT as `compare` does (affine, cement masked)")) +
                    "; its cement: " + fmt(cement.segmentation.volumeMl, "%.3f") + " ml, mean spreading distance " +
                    fmt(cement.spreadingMm, "%.2f") + " mm";
        runner->setReference(std::move(cement));
      } else if (plan.sizeStudy) {
        for (const auto& run : plan.sizeRuns())
          if (run.reference)
            reference = "the finest run, " + run.integrator + " at r " + study::radiusLabel(run.particleRadiusMm) +
                        " mm (the smallest radius with the most faithful integrator listed: central-difference, "
                        "then explicit, then overdamped); it runs first";
      }
    });
    if (!farm.coordinator()) { // a worker: injections only
      runner->runStudy(farm);
      return 0;
    }

    // 2. The runs; after each, every table is rewritten (atomically) and one progress line printed.
    std::vector<study::StudyRow> sizeRows, viscosityRows;
    const scene::SceneConfig& s = plan.baseScene;
    const int threads = omp_get_max_threads();
    auto seconds = [&start] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    auto runsWall = [&] {
      double sum = 0;
      for (const auto* rows : {&sizeRows, &viscosityRows})
        for (const auto& r : *rows) sum += r.wallTimeS + r.analysisTimeS;
      return sum;
    };
    auto writeTables = [&] {
      std::vector<std::string> preamble{
          "CT `" + a->ct + "`; scene `" + a->scene + "` as run: " + fmt(s.volumeMl, "%g") + " ml at " +
              fmt(s.flowRateMlPerS, "%g") + " ml/s, " + fmt(s.viscosityPaS, "%g") + " Pa.s, model preset " +
              s.modelPreset + ", tip (" + fmt((*s.tipMm)[0], "%g") + ", " + fmt((*s.tipMm)[1], "%g") + ", " +
              fmt((*s.tipMm)[2], "%g") + ") mm; " + std::to_string(threads) + " OpenMP thread(s)" +
              (farm.ranks() > 1 ? " per rank, " + std::to_string(farm.ranks()) +
                                      " MPI ranks (rank 0 scores and writes, the others inject)."
                                : std::string(".")),
          "Cement in every volume: minus the CT, " + imaging::describeThresholdRule(options.segmentation) +
              ", the component at the tip, as `cementsph compare` segments it."};
      if (!sizeRows.empty())
        preamble.push_back(
            "Reference: " + reference +
            ". Surface error: the paper's error, the larger of the two directed mean distances between the "
            "cement isosurfaces; spreading diff.: the run's mean spreading distance of its cement minus the "
            "reference's; Dice of the two cement masks. Wall time: the inject runner's, porous-solid set-up "
            "included.");
      preamble.push_back("Runs: " + fmt(runsWall(), "%.1f") + " s (injections and cement analysis); study " +
                         fmt(seconds(), "%.1f") + " s in all so far.");
      std::error_code ec;
      fs::create_directories(out, ec);
      if (ec) throw std::runtime_error(out.string() + ": cannot create the output folder: " + ec.message());
      if (!sizeRows.empty())
        imaging::writeTextAtomically((out / "study.csv").string(), study::sizeStudyCsv(sizeRows));
      if (!viscosityRows.empty())
        imaging::writeTextAtomically((out / "spreading_vs_viscosity.csv").string(), study::viscosityCsv(viscosityRows));
      imaging::writeTextAtomically((out / "study.md").string(),
                                   study::studyMarkdown(sizeRows, viscosityRows, preamble));
      json j;
      j["ct"] = a->ct;
      j["scene_file"] = a->scene;
      j["scene"] = scene::toJson(s);
      j["radii_mm"] = plan.sizeStudy ? json(plan.radiiMm) : json::array();
      j["integrators"] = plan.sizeStudy ? json(plan.integrators) : json::array();
      j["viscosities_pa_s"] = plan.viscositiesPaS;
      j["reference"] = plan.sizeStudy ? json(reference) : json(nullptr);
      j["reference_ct"] = plan.referenceIsCt ? json(a->referenceCt) : json(nullptr);
      j["threads"] = threads; // OpenMP threads of each rank
      j["mpi_ranks"] = farm.ranks();
      j["size_runs_done"] = sizeRows.size();
      j["viscosity_runs_done"] = viscosityRows.size();
      j["runs_wall_time_s"] = runsWall();
      j["study_wall_time_s"] = seconds();
      j["provenance"] = cementsph::provenance::toJson();
      imaging::writeTextAtomically((out / "study.json").string(), j.dump(2) + "\n");
    };
    int status = 0;
    const std::size_t sizePlanned = plan.sizeStudy ? plan.sizeRuns().size() : 0;
    const std::size_t viscosityPlanned = plan.viscosityRuns().size();
    runner->runStudy(farm, [&](const std::vector<study::StudyRow>& rows, std::size_t) {
      const study::StudyRow& last = rows.back();
      const bool size = last.spec.sweep == study::StudyRunSpec::Sweep::ParticleSize;
      auto& into = size ? sizeRows : viscosityRows;
      into.push_back(last);
      if (!last.ok()) status = 3;
      writeTables();
      std::cerr << progressLine(last, into.size(), size ? sizePlanned : viscosityPlanned, size ? "size" : "viscosity")
                << (farm.ranks() > 1 ? " [rank " + std::to_string(last.rank) + "]" : std::string()) << std::endl;
    });
    writeTables();

    // 3. Pictures, after the tables, so a rendering failure never loses the numbers (exit 3, as compare).
    std::vector<std::string> written{"study.md", "study.json"};
    if (!sizeRows.empty()) written.push_back("study.csv");
    if (!viscosityRows.empty()) written.push_back("spreading_vs_viscosity.csv");
    auto picture = [&](const char* name, const auto& draw) {
      try {
        draw(out / name);
        written.push_back(name);
      } catch (const std::exception& e) {
        std::cerr << "cementsph study: picture " << name << " not written (the tables are): " << e.what() << "\n";
        status = 3;
      }
    };
    if (!a->noPictures && !sizeRows.empty())
      picture("error_vs_wall_time.png",
              [&](const fs::path& png) { study::writeErrorVsWallTimePlot(sizeRows, png); });
    if (!a->noPictures && !viscosityRows.empty())
      picture("spreading_vs_viscosity.png",
              [&](const fs::path& png) { study::writeSpreadingVsViscosityPlot(viscosityRows, png); });

    std::cout << "study done: " << sizeRows.size() + viscosityRows.size() << " runs, " << fmt(seconds(), "%.1f")
              << " s wall; wrote";
    for (const auto& name : written) std::cout << " " << (out / name).string();
    std::cout << "\n";
    if (status == 3) std::cerr << "cementsph study: some runs failed or pictures are missing (exit status 3)\n";
    return status;
  };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND_OVER_RANKS(study_command, "study",
                           "Particle-size study (paper Fig. 6) as speed against error: radii x integrators, wall "
                           "time, particles, error against the finest run or a post-operative CT; viscosity sweep "
                           "(Fig. 8)",
                           setupStudy)
