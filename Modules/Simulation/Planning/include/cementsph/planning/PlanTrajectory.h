// The plan's trajectory checked against the anatomy before any injection runs (issue 20, item 4): does the
// straight shaft from the entry point stay in the pedicle and the vertebra (anatomy/Trajectory.h has the rule)?
//
// The shaft checked runs from the entry to the target's foot on the trajectory (the target itself when the
// direction is the entry -> target line, as `plan` makes it without --direction), or to the deepest tip
// (--max-depth-mm) where that is shallower or the target lies behind the entry.
// The anatomy: the scene's label map (labels_path, label_table) if it has one, else the CT-only bone rule
// (VertebraAnatomy.h) seeded at the target, on the CT's own grid (its direction matrix included: nothing is
// resampled) over the box that holds the shaft and a 100 mm cube about the target (a vertebra and its discs,
// as the injection's anatomy), clipped to the CT.
#pragma once

#include "cementsph/anatomy/Trajectory.h"
#include "cementsph/anatomy/VertebraAnatomy.h"
#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/scene/SceneConfig.h"

#include <Eigen/Core>

#include <vector>

namespace cementsph::planning {

struct PlanRequest;

// The anatomy (labels or bone rule, on the CT's own grid) over the box holding the points given and a
// cubeMm cube about seedMm, the bone rule seeded at seedMm. std::invalid_argument for a label map that is not
// on the CT's grid or a bad label_table.
anatomy::Anatomy anatomyAround(const imaging::ImageType* ct, const scene::SceneConfig& scene,
                               const Eigen::Vector3d& seedMm, const std::vector<Eigen::Vector3d>& alsoHold,
                               double cubeMm = 100.0);

// Where the checked shaft ends (see above).
Eigen::Vector3d shaftEndMm(const PlanRequest& request);

// The check (never throws for a refused shaft: the caller decides; see PlanRequest::allowCanalCrossing).
anatomy::TrajectoryCheck checkPlanTrajectory(const imaging::ImageType* ct, const PlanRequest& request);

} // namespace cementsph::planning
