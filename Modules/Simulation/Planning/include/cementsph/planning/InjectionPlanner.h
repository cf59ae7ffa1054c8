// `cementsph plan` (issue "Planning at scale", item 1): where along a trajectory to put the cannula's tip and
// how much cement to inject so that a target region is covered within the syringe-pressure and leakage
// limits. Each evaluation is a full injection (runInjection: the default voxel-grid Darcy model, continuum
// bone on a clinical CT); the optimiser is NLopt's BOBYQA (Powell 2009, a derivative-free trust-region
// method on quadratic models, with bounds), chosen because an injection has no gradient and costs a
// fraction of a second to seconds.
//
// Parameters: tip depth d along the trajectory (tip = entry + d direction, mm) and volume V (ml), within
// bounds. Objective (maximised): coverage - 5 (max(0, p_syringe / p_max - 1) + max(0, leak - leak_max) / 0.1 ml),
// coverage the fraction of the target sphere's volume in voxels at least half filled with cement. A plan
// whose injection cannot run (a tip in cortex, outside the CT) scores -1 and says why.
// Not done: a second tip.
#pragma once

#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/scene/SceneConfig.h"

#include <Eigen/Core>
#include <vtkPolyData.h>
#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

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
  int maxEvaluations = 40;
  // Throws std::invalid_argument (one line naming the option) for bounds out of order, a zero direction,
  // a target or trajectory that leaves the CT.
  void validate(const imaging::ImageType* ct) const;
};

struct PlanEvaluation {
  int index = 0;
  double depthMm = 0, volumeMl = 0;
  Eigen::Vector3d tipMm = Eigen::Vector3d::Zero();
  double coverage = 0, syringeMpa = 0, leakageMl = 0, objective = -1;
  bool withinLimits = false;
  std::string failure; // why the injection could not run (empty when it ran)
  nlohmann::json toJson() const;
};

struct PlanResult {
  PlanEvaluation best;
  std::vector<PlanEvaluation> evaluations;
  std::string stopReason;
  nlohmann::json toJson(const PlanRequest& request) const;
  std::string csv() const; // one row per evaluation
};

// The fraction of a sphere's volume covered by the cement points of an injection (VoxelDarcyInjection.h's
// particles: cement_volume_mm3, fill_fraction and porosity per voxel centre).
double targetCoverage(vtkPolyData* cementVoxels, const Eigen::Vector3d& centreMm, double radiusMm);

PlanResult planInjection(const imaging::ImageType* ct, const PlanRequest& request,
                         const std::function<void(const PlanEvaluation&)>& onEvaluation = {});

} // namespace cementsph::planning
