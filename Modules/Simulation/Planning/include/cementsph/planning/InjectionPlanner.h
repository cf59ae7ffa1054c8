// `cementsph plan` (issue "Planning at scale", item 1): where along a trajectory to put the cannula's tip and
// how much cement to inject so that a target region is covered within the syringe-pressure and leakage
// limits. Each evaluation is a full injection (vtkSPHInjectionFilter without its image outputs, over the one
// driver runInjection: the default voxel-grid Darcy model, continuum bone on a clinical CT); the optimiser is NLopt's BOBYQA (Powell 2009, a derivative-free trust-region
// method on quadratic models, with bounds), chosen because an injection has no gradient and costs a
// fraction of a second to seconds.
//
// Parameters: tip depth d along the trajectory (tip = entry + d direction, mm) and volume V (ml), within
// bounds. Objective (maximised, planObjective): coverage - c V - 5 (max(0, p_syringe / p_max - 1) +
// max(0, leak - leak_max) / 0.1 ml), coverage the fraction of the target sphere's volume in voxels at least half
// filled with cement, c the cost of cement (volumeCostPerMl, 0.01 per ml by default). The trade-off: one more
// ml of cement is worth it only if it covers at least one more percent of the target, so of two plans with the
// same coverage the one with less cement wins (less cement, less leakage risk and heat). Leakage is the
// injection's (cement outside the target vertebra where the anatomy is known: Modules/Simulation/Anatomy). A
// plan whose injection cannot run (a tip in cortex, outside bone, outside the CT) scores -1 and says why; one
// whose cement reaches the scan's or the region's edge is outside the limits (objective - 5) and says so.
//
// The volume trim (the last step; the trade-off made explicit): a local search on a curve whose coverage
// saturates (coverage rises until the cement fills the target, then stays) stops anywhere on the flat part; of
// two plans with the same coverage the one with less cement is the plan. So at the best plan's depth the volume is
// bisected (between --min-volume-ml and the best's, to 0.05 ml: up to 7 more injections) for the smallest whose
// coverage is within trimCoverageTolerance (0.01: the coverage is counted on voxels, the target ball's and the
// cement's half-filled front layer, to about that) of the best's and which keeps within the limits. Coverage at one
// depth does not fall as the volume grows (an injection of V is the first V of a larger one), so the bisection
// finds the smallest such volume to 0.05 ml. The trimmed plan is `best`; the search's own best stays in
// `searchBest` (plan.json "search_best"), and why_best says what the trim saved. Not for a two-tip plan (its
// second tip's share would move with the volume).
//
// A second tip (secondTip): the two-depth technique on one trajectory. The cement goes in at depth d, then
// the cannula is withdrawn to d2 = d_min + t (d - d_min), t in [0, 0.9], and the last share s in
// [0.2, 0.8] of V goes in there (scene keys second_tip_withdrawal_mm, second_tip_volume_ml): four
// parameters (d, V, t, s) instead of two.
//
// Several starts (multi-start BOBYQA): start s of K begins at depth min + (s + 1/2)(max - min)/K and the
// largest volume, with the evaluation budget shared equally; the best plan of all starts wins (the first
// on a tie). A trajectory through bone with cortex, canal and soft tissue is a rugged landscape: one local
// search settles in the first basin it finds. The starts are independent, so under mpirun they run on the
// worker ranks (parallel::CaseFarm), with the same evaluations as one process makes one after another.
#pragma once

#include "cementsph/anatomy/Trajectory.h"
#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/scene/SceneConfig.h"

#include <Eigen/Core>
#include <vtkPolyData.h>
#include <nlohmann/json.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace cementsph::parallel {
class CaseFarm;
}

namespace cementsph::planning {

struct PlanRequest {
  scene::SceneConfig scene;                     // the cement, rate, viscosity and model keys (tip and volume are planned)
  Eigen::Vector3d entryMm = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ(); // along the trajectory, into the bone
  double minDepthMm = 0.0, maxDepthMm = 20.0;
  Eigen::Vector3d targetCentreMm = Eigen::Vector3d::Zero();
  double targetRadiusMm = 5.0;
  double minVolumeMl = 0.5, maxVolumeMl = 4.0;  // the volume budget
  double maxSyringeMpa = 3.0, maxLeakageMl = 0.0;
  double volumeCostPerMl = 0.01;                // coverage (fraction) one ml of cement must buy
  int maxEvaluations = 40;                      // over all starts
  int starts = 3;                               // independent BOBYQA starts along the trajectory
  bool secondTip = false;                       // also plan a second, shallower tip on the trajectory
  double trimCoverageTolerance = 0.01;          // coverage the volume trim may give up (see above); 0: no trim
  // The trajectory against the anatomy (PlanTrajectory.h): computed once before the plan (planInjection does it
  // when absent). A shaft through the spinal canal is refused unless allowCanalCrossing (a deliberate path).
  std::optional<anatomy::TrajectoryCheck> trajectoryCheck;
  bool allowCanalCrossing = false;
  int parameters() const { return secondTip ? 4 : 2; }
  // Throws std::invalid_argument (one line naming the option) for bounds out of order, a zero direction,
  // a target or trajectory that leaves the CT.
  void validate(const imaging::ImageType* ct) const;
};

// The objective of a plan (see the header comment): coverage less the cement's cost and the limits' penalty.
double planObjective(const struct PlanRequest& request, double coverage, double volumeMl, double syringeMpa,
                     double leakageMl);

struct PlanEvaluation {
  int index = 0;
  int start = 0;    // the start it belongs to
  double depthMm = 0, volumeMl = 0;
  Eigen::Vector3d tipMm = Eigen::Vector3d::Zero();
  bool secondTip = false;                          // the plan has a second tip
  double secondDepthMm = 0, secondVolumeMl = 0;    // where, and how much of volumeMl goes in there
  Eigen::Vector3d secondTipMm = Eigen::Vector3d::Zero();
  double coverage = 0, syringeMpa = 0, leakageMl = 0, objective = -1;
  bool withinLimits = false;
  std::string failure; // why the injection could not run (empty when it ran)
  std::vector<std::string> warnings; // the injection's edge warnings (each a limit: objective - 5)
  bool volumeTrim = false;           // made by the volume trim after the search (not by BOBYQA)
  nlohmann::json toJson() const;
};

// One start's local search.
struct PlanStart {
  int index = 0;
  double depthMm = 0, volumeMl = 0; // where it began
  int rank = 0;                     // the MPI rank that ran it (0 in one process)
  std::string stopReason;           // NLopt's, or why the start failed
  int evaluations = 0;
  nlohmann::json toJson() const;
};

struct PlanResult {
  PlanEvaluation best;                      // the plan: the search's best, its volume trimmed (see above)
  PlanEvaluation searchBest;                // the search's best (highest objective), before the trim
  std::vector<PlanEvaluation> evaluations;  // every start's, in start order
  std::vector<PlanStart> starts;
  std::string stopReason;                   // the best plan's start's
  int mpiRanks = 1;
  anatomy::TrajectoryCheck trajectory;      // the shaft against the anatomy (PlanTrajectory.h)
  nlohmann::json toJson(const PlanRequest& request) const;
  std::string csv() const; // one row per evaluation
};

// Throws std::invalid_argument (one line: the crossing and what to do) for a shaft through the spinal canal
// unless request.allowCanalCrossing.
void requireASafeTrajectory(const anatomy::TrajectoryCheck& check, const PlanRequest& request);

// The fraction of a sphere's volume covered by the cement points of an injection (VoxelDarcyInjectionModel.cpp's
// particles: cement_volume_mm3, fill_fraction and porosity per voxel centre).
double targetCoverage(vtkPolyData* cementVoxels, const Eigen::Vector3d& centreMm, double radiusMm);

// Every rank of an MPI job calls it (farm: parallel::caseFarm()); the result is complete on rank 0 only.
// Throws std::invalid_argument (one line) for a request that fails validate() or a trajectory through the
// spinal canal (unless allowCanalCrossing).
// onEvaluation sees each evaluation on rank 0, a start's all at once as that start comes in.
PlanResult planInjection(const imaging::ImageType* ct, const PlanRequest& request,
                         const std::function<void(const PlanEvaluation&)>& onEvaluation = {},
                         parallel::CaseFarm* farm = nullptr);

} // namespace cementsph::planning
