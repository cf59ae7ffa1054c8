#include "cementsph/planning/PlanOutputs.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/provenance/Provenance.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/sph/Simulation.h"
#include "vtkSPHInjectionFilter.h"

#include <vtkPolyData.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace cementsph::planning {

void requireAnInjectionThatRan(const PlanResult& plan) {
  // A plan none of whose injections ran is no plan: a failed run, nothing written.
  if (std::all_of(plan.evaluations.begin(), plan.evaluations.end(),
                  [](const PlanEvaluation& e) { return !e.failure.empty(); }))
    throw sph::SimulationError("every one of the " + std::to_string(plan.evaluations.size()) +
                               " injections failed (the first: " +
                               (plan.evaluations.empty() ? std::string("none ran") : plan.evaluations.front().failure) +
                               "); no plan written: check the trajectory and the scene");
}

void writePlanTables(const PlanResult& plan, const PlanRequest& request, const std::filesystem::path& out) {
  std::filesystem::create_directories(out);
  nlohmann::json planJson = plan.toJson(request);
  planJson["provenance"] = provenance::toJson();
  imaging::writeTextAtomically((out / "plan.json").string(), planJson.dump(2) + "\n");
  imaging::writeTextAtomically((out / "plan.csv").string(), plan.csv());
}

scene::SceneConfig bestPlanScene(const PlanResult& plan, const PlanRequest& request) {
  scene::SceneConfig s = request.scene;
  s.tipMm = plan.best.tipMm;
  s.direction = request.direction.normalized();
  s.explicitKeys.insert("direction"); // the trajectory is given, whatever its value (a vertebra needs one)
  s.volumeMl = plan.best.volumeMl;
  if (plan.best.secondTip) {
    s.secondTipWithdrawalMm = plan.best.depthMm - plan.best.secondDepthMm;
    s.secondTipVolumeMl = plan.best.secondVolumeMl;
  }
  return s;
}

namespace {
// A label map (any scalar type, values 0..255) as a MaskType, its geometry kept.
imaging::MaskType::Pointer labelsAsMask(const imaging::ImageType* image) {
  auto mask = imaging::MaskType::New();
  mask->CopyInformation(image);
  mask->SetRegions(image->GetLargestPossibleRegion());
  mask->Allocate();
  const float* in = image->GetBufferPointer();
  std::uint8_t* out = mask->GetBufferPointer();
  for (std::size_t i = 0, n = image->GetLargestPossibleRegion().GetNumberOfPixels(); i < n; ++i)
    out[i] = std::uint8_t(std::lround(in[i]));
  return mask;
}
} // namespace

scene::InjectionRunResult runBestPlan(const imaging::ImageType* ct, const PlanResult& plan, const PlanRequest& request,
                                      const std::filesystem::path& outDir) {
  // Through the VTK filter, as inject runs (the same driver, files and outputs on the CT's own grid).
  auto filter = vtkSmartPointer<vtkSPHInjectionFilter>::New();
  filter->SetInputDataObject(0, imaging::toVtk(ct));
  filter->SetScene(bestPlanScene(plan, request));
  filter->SetOutputDirectory(outDir.string());
  filter->Update();
  filter->RethrowIfFailed();
  // The typed result (summary, metrics, points, the anatomy labels), with the images the filter's outputs hold.
  scene::InjectionRunResult run = *filter->GetResult();
  run.simulatedCtFile = imaging::imageFromVtk(filter->GetSimulatedCTOutput());
  run.cementLabelsFile = labelsAsMask(imaging::imageFromVtk(filter->GetLabelMapOutput()));
  return run;
}

vtkSmartPointer<vtkImageData> labelsWithUncoveredTarget(const scene::InjectionRunResult& run,
                                                        const Eigen::Vector3d& targetCentreMm, double targetRadiusMm) {
  // The files' grid (the input CT's, as simulatedCtFile and anatomyLabelsFile) when the run wrote them.
  const imaging::MaskType* cement = run.cementLabelsFile ? run.cementLabelsFile.GetPointer() : run.cementLabels.GetPointer();
  if (!cement) throw std::runtime_error("the injection made no cement label map");
  auto labels = imaging::toVtk(cement);
  int dims[3];
  labels->GetDimensions(dims);
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i) {
        double p[3];
        labels->TransformContinuousIndexToPhysicalPoint(i, j, k, p);
        if ((Eigen::Vector3d(p[0], p[1], p[2]) - targetCentreMm).norm() <= targetRadiusMm &&
            labels->GetScalarComponentAsDouble(i, j, k, 0) == 0)
          labels->SetScalarComponentFromDouble(i, j, k, 0, 3);
      }
  return labels;
}

} // namespace cementsph::planning
