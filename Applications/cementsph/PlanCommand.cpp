// cementsph plan: the tip depth along a trajectory and the volume that cover a target within the syringe
// and leakage limits (Modules/Simulation/Planning/InjectionPlanner.h). Writes DIR/plan.json (the best plan,
// every evaluation, the optimiser's stop reason), DIR/plan.csv, DIR/convergence.png and DIR/best/ (the best
// plan's injection, with cement_slices.png through the target: cement blue, leaks in their classes' colours, the
// uncovered target yellow, the cannula and the vertebra's outline as inject draws them).
// A thin layer: the planner, plan.json/plan.csv and the best plan's run are CementSPH::Planning's
// (InjectionPlanner.h, PlanOutputs.h); this file parses the options, draws the pictures and prints the summary.
#include "CommandRegistry.h"
#include "OutputFiles.h"
#include "SceneOverrides.h"

#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/parallel/CaseFarm.h"
#include "cementsph/planning/InjectionPlanner.h"
#include "cementsph/planning/PlanOutputs.h"
#include "cementsph/planning/PlanTrajectory.h"
#include "cementsph/rendering/CementSlices.h"
#include "cementsph/rendering/XYPlot.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/scene/SceneConfig.h"

#include <omp.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>

namespace {

namespace fs = std::filesystem;

struct PlanArgs {
  std::string ct, scene, out, labels;
  std::vector<double> entry, direction, target;
  double targetRadiusMm = 5, minDepthMm = 0, maxDepthMm = 20, minVolumeMl = 0.5, maxVolumeMl = 4;
  double maxSyringeMpa = 3.0, maxLeakageMl = 0.0, volumeCostPerMl = 0.01;
  int maxEvaluations = 40, starts = 3, threads = 0;
  bool quiet = false, secondTip = false, allowCanalCrossing = false, maxDepthGiven = false;
};

Eigen::Vector3d vec(const std::vector<double>& v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

// --direction as a unit vector, scaled by its largest component first: the norm of (1, 1, 1e308) overflows, and
// the vector then normalised to zero ("the shaft ... has no length", naming no option).
Eigen::Vector3d unitDirection(const std::vector<double>& v) {
  const Eigen::Vector3d d = vec(v);
  const double largest = d.cwiseAbs().maxCoeff();
  if (!(largest > 0)) throw std::invalid_argument("--direction 0,0,0 points nowhere: give a vector into the bone");
  return (d / largest).normalized();
}

using namespace cementsph;

planning::PlanRequest planRequest(const PlanArgs& a) {
  planning::PlanRequest r;
  // The scene's tip and volume are the plan's to choose: the entry stands in for the tip while reading it.
  scene::SceneSettings entryAsTip;
  entryAsTip.tipMm = {a.entry[0], a.entry[1], a.entry[2]};
  r.scene = scene::loadSceneFile(a.scene, entryAsTip);
  if (!a.labels.empty()) {
    r.scene.labelsPath = a.labels;
    r.scene.explicitKeys.insert("labels_path");
  }
  r.entryMm = vec(a.entry);
  r.targetCentreMm = vec(a.target);
  // Without --direction the trajectory is the entry -> target line, and the deepest tip the target itself
  // unless --max-depth-mm says otherwise.
  r.direction = a.direction.empty() ? Eigen::Vector3d(r.targetCentreMm - r.entryMm) : unitDirection(a.direction);
  if (a.direction.empty() && !(r.direction.norm() > 0))
    throw std::invalid_argument("--entry-mm and --target-mm are the same point: give the trajectory a length or a --direction");
  r.minDepthMm = a.minDepthMm;
  r.maxDepthMm = a.direction.empty() && !a.maxDepthGiven ? r.direction.norm() : a.maxDepthMm;
  r.allowCanalCrossing = a.allowCanalCrossing;
  r.targetRadiusMm = a.targetRadiusMm;
  r.minVolumeMl = a.minVolumeMl;
  r.maxVolumeMl = a.maxVolumeMl;
  r.maxSyringeMpa = a.maxSyringeMpa;
  r.maxLeakageMl = a.maxLeakageMl;
  r.volumeCostPerMl = a.volumeCostPerMl;
  r.maxEvaluations = a.maxEvaluations;
  r.starts = a.starts;
  r.secondTip = a.secondTip;
  return r;
}

// convergence.png: every evaluation's objective and the best so far.
void drawConvergence(const planning::PlanResult& plan, const fs::path& png) {
  rendering::PlotSpec spec;
  spec.title = "Plan: objective per evaluation";
  spec.xLabel = "evaluation";
  spec.yLabel = "coverage - penalties";
  rendering::PlotSeries each, best;
  each.name = "evaluation";
  each.style = rendering::PlotSeries::Style::Points;
  best.name = "best so far";
  best.style = rendering::PlotSeries::Style::Line;
  best.rgb = {214, 39, 40};
  double sofar = -1e300;
  for (const auto& e : plan.evaluations) {
    each.x.push_back(e.index);
    each.y.push_back(e.objective);
    sofar = std::max(sofar, e.objective);
    best.x.push_back(e.index);
    best.y.push_back(sofar);
  }
  spec.series = {each, best};
  rendering::writePlotPng(spec, png);
}

void printEvaluation(const planning::PlanEvaluation& e) {
  std::cerr << "plan " << e.index << " (start " << e.start << (e.volumeTrim ? ", volume trim" : "") << "): depth " << e.depthMm << " mm, " << e.volumeMl
            << " ml: coverage " << e.coverage << ", syringe " << e.syringeMpa << " MPa, leak " << e.leakageMl << " ml"
            << (e.failure.empty() ? "" : " (" + e.failure + ")") << "\n";
}

void printSummary(const planning::PlanResult& plan, const std::string& out) {
  const auto& b = plan.best;
  std::cout << "plan: depth " << b.depthMm << " mm (tip " << b.tipMm.x() << "," << b.tipMm.y() << "," << b.tipMm.z()
            << " mm), " << b.volumeMl << " ml"
            << (b.secondTip ? " (" + std::to_string(b.secondVolumeMl) + " ml of it at a second tip, depth " +
                                  std::to_string(b.secondDepthMm) + " mm)"
                            : std::string())
            << ": coverage " << b.coverage << ", syringe " << b.syringeMpa << " MPa, leak " << b.leakageMl << " ml, "
            << (b.withinLimits ? "within" : "OUTSIDE") << " the limits; " << plan.evaluations.size()
            << " injections in " << plan.starts.size() << " starts"
            << (b.volumeTrim ? " and the volume trim (from " + std::to_string(plan.searchBest.volumeMl) + " ml)" : std::string())
            << (plan.mpiRanks > 1 ? " over " + std::to_string(plan.mpiRanks) + " MPI ranks" : std::string()) << ", "
            << plan.stopReason << "; results in " << out << "\n";
}

int runPlan(const PlanArgs& a) {
  // Under mpirun the starts are shared among the ranks (Modules/Parallel/CaseFarm); rank 0 writes.
  parallel::CaseFarm& farm = parallel::caseFarm();
  if (a.threads > 0) omp_set_num_threads(a.threads);
  else if (farm.ranks() > 1 && !std::getenv("OMP_NUM_THREADS"))
    omp_set_num_threads(farm.threadsPerRank(omp_get_num_procs()));
  planning::PlanRequest r;
  imaging::ImageType::Pointer image;
  farm.agree([&] {
    r = planRequest(a);
    image = imaging::readVolume(a.ct);
    r.validate(image); // before anything is written
    // The shaft against the anatomy, once: through the canal it is refused here, one line, nothing written.
    r.trajectoryCheck = planning::checkPlanTrajectory(image, r);
    planning::requireASafeTrajectory(*r.trajectoryCheck, r);
  });
  if (farm.coordinator() && r.trajectoryCheck->verdict != "clear")
    std::cerr << "plan: warning: " << r.trajectoryCheck->message
              << (r.trajectoryCheck->refused() ? " (allowed by --allow-canal-crossing)" : "") << "\n";
  const planning::PlanResult plan = planning::planInjection(
      image, r, [&](const planning::PlanEvaluation& e) { if (!a.quiet) printEvaluation(e); }, &farm);
  if (!farm.coordinator()) return 0; // a worker: its starts went to rank 0
  planning::requireAnInjectionThatRan(plan);
  const fs::path out(a.out);
  planning::writePlanTables(plan, r, out);
  app::PictureSteps pictures("plan");
  pictures.draw("convergence.png", out / "convergence.png", [&](const fs::path& png) { drawConvergence(plan, png); });
  // The best plan's injection, its files and its picture with the target (the cement missed yellow).
  if (plan.best.failure.empty()) {
    const scene::InjectionRunResult run = planning::runBestPlan(image, plan, r, out / "best");
    pictures.draw("best/cement_slices.png", out / "best" / "cement_slices.png", [&](const fs::path& png) {
      const auto labels = planning::labelsWithUncoveredTarget(run, r.targetCentreMm, r.targetRadiusMm);
      // inject's marks (the cannula, each leak in its class's colour), through the target.
      rendering::InjectionMarks marks;
      marks.tipMm = {plan.best.tipMm.x(), plan.best.tipMm.y(), plan.best.tipMm.z()};
      marks.direction = {r.direction.x(), r.direction.y(), r.direction.z()};
      for (const auto& site : run.summary.leakageSites)
        marks.leaks.push_back({{site.positionMm, site.siteClass}, site.volumeMl});
      // The vertebra the run judged leakage by (--labels or the bone rule; the result's, as best/anatomy_labels.nrrd
      // holds it), outlined.
      const auto vertebra = run.anatomyLabelsFile ? imaging::toVtk(run.anatomyLabelsFile.GetPointer()) : nullptr;
      marks.vertebraMask = vertebra;
      marks.vertebraLabel = 1; // anatomy::TissueClass::TargetVertebra
      rendering::writeCementSlices(imaging::toVtk(run.simulatedCtFile.GetPointer()), labels,
                                   {r.targetCentreMm.x(), r.targetCentreMm.y(), r.targetCentreMm.z()}, png,
                                   marks.options());
    });
  }
  printSummary(plan, a.out);
  return pictures.status();
}

cementsph::app::CommandRunner setupPlan(CLI::App& sub) {
  auto a = std::make_shared<PlanArgs>();
  sub.add_option("--ct", a->ct, "CT volume in HU (file or DICOM directory)")->required();
  sub.add_option("--scene", a->scene, "Scene file: cement, rate, viscosity, model keys (tip and volume are planned)")->required();
  sub.add_option("--out", a->out, "Output directory (plan.json, plan.csv, convergence.png, best/)")->required();
  sub.add_option("--entry-mm", a->entry,
                 "Trajectory entry point x,y,z in mm (the CT's LPS frame); the shaft from it is checked against the "
                 "anatomy (pedicle, canal, disc, cortex) before any injection runs")
      ->delimiter(',')->expected(3)->required();
  sub.add_option("--direction", a->direction,
                 "Trajectory direction x,y,z, into the bone (default: from --entry-mm towards --target-mm)")
      ->delimiter(',')->expected(3);
  sub.add_option("--min-depth-mm", a->minDepthMm, "Shallowest tip along the trajectory (mm from the entry)");
  sub.add_option("--max-depth-mm", a->maxDepthMm,
                 "Deepest tip along the trajectory (mm from the entry; default 20, or the target's distance without "
                 "--direction)")
      ->each([a](const std::string&) { a->maxDepthGiven = true; });
  sub.add_option("--labels", a->labels,
                 "Label map on the CT's grid (TotalSegmentator, 3D Slicer) for the trajectory check and the "
                 "leakage, instead of the CT bone rule (scene key labels_path; label_table says which label is what)");
  sub.add_flag("--allow-canal-crossing", a->allowCanalCrossing,
               "Plan even when the shaft crosses the spinal canal (refused otherwise); the crossing stays a "
               "warning in plan.json and on stderr");
  sub.add_option("--target-mm", a->target, "Target sphere centre x,y,z in mm")->delimiter(',')->expected(3)->required();
  sub.add_option("--target-radius-mm", a->targetRadiusMm, "Target sphere radius in mm");
  sub.add_option("--min-volume-ml", a->minVolumeMl, "Smallest volume to consider (ml)");
  sub.add_option("--max-volume-ml", a->maxVolumeMl, "Volume budget (ml)");
  sub.add_option("--max-syringe-mpa", a->maxSyringeMpa, "Syringe pressure limit (MPa)");
  sub.add_option("--max-leakage-ml", a->maxLeakageMl, "Leakage limit (ml; 0: none allowed)");
  sub.add_option("--volume-cost-per-ml", a->volumeCostPerMl,
                 "Coverage (fraction of the target) one ml of cement must buy: of two plans covering the same, the "
                 "one with less cement wins (default 0.01)")
      ->check(CLI::Range(0.0, 1.0));
  sub.add_option("--max-evaluations", a->maxEvaluations, "Injections the optimiser may run, over all starts");
  sub.add_option("--starts", a->starts,
                 "Independent BOBYQA starts spread along the trajectory (under mpirun, one per free rank at a time)");
  sub.add_option("--threads", a->threads, "OpenMP threads (0: the cores the load average leaves free)");
  sub.add_flag("--second-tip", a->secondTip,
               "Also plan a second, shallower tip on the trajectory: the cannula withdrawn part-way through the "
               "volume (the two-depth technique)");
  sub.add_flag("--quiet", a->quiet, "No line per evaluation");
  return [a, &sub]() { return app::namingTheOptions(sub, a->scene, [&] { return runPlan(*a); }); };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND_OVER_RANKS(plan, "plan",
                           "Plan an injection: the tip depth along a trajectory and the volume that cover a target "
                           "within syringe-pressure and leakage limits (NLopt BOBYQA over full injections)",
                           setupPlan)
