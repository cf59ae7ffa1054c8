// What `cementsph plan` does with a finished plan: refuse a plan none of whose injections ran, write plan.json
// and plan.csv, run the best plan's injection again with its files (DIR/best/), and mark the target's voxels the
// cement missed for its picture. Here, beside the planner, so the command holds no schema and no physics.
#pragma once

#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/planning/InjectionPlanner.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/scene/SceneConfig.h"

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include <filesystem>

namespace cementsph::planning {

// Throws sph::SimulationError (a failed run: nothing is to be written) when every evaluation failed.
void requireAnInjectionThatRan(const PlanResult& plan);

// Creates out; writes plan.json (PlanResult::toJson with provenance) and plan.csv, each atomically.
void writePlanTables(const PlanResult& plan, const PlanRequest& request, const std::filesystem::path& out);

// The best plan's scene: the request's with the plan's tip, the trajectory's direction, its volume and, for a
// second tip, the withdrawal and the volume given there.
scene::SceneConfig bestPlanScene(const PlanResult& plan, const PlanRequest& request);

// The best plan's injection through vtkSPHInjectionFilter, as inject runs it, its files written into outDir. The
// result holds the summary, metrics, cement points and the files' images on the CT's own grid (simulatedCtFile,
// cementLabelsFile from the filter's outputs 0 and 1, anatomyLabelsFile from anatomy_labels.nrrd); not the
// region's images. The plan's evaluations call the driver directly (InjectionPlanner.cpp says why).
scene::InjectionRunResult runBestPlan(const imaging::ImageType* ct, const PlanResult& plan, const PlanRequest& request,
                                      const std::filesystem::path& outDir);

// The run's cement label map (on the files' grid, cementLabelsFile, when it wrote files; else on its region's
// grid) with the target sphere's voxels that hold no cement as label 3. Throws std::runtime_error when the run
// made no label map.
vtkSmartPointer<vtkImageData> labelsWithUncoveredTarget(const scene::InjectionRunResult& run,
                                                        const Eigen::Vector3d& targetCentreMm, double targetRadiusMm);

} // namespace cementsph::planning
