// What `cementsph plan` does with a finished plan (PlanOutputs.h): the best plan's scene, the target's missed
// voxels for the picture, and the refusal of a plan none of whose injections ran. Oracles: numbers the test sets,
// and the lattice count of a sphere (the voxel centres within 2 voxels of a voxel centre: 1 + 6 + 12 + 8 + 6 = 33,
// at distances 0, 1, sqrt 2, sqrt 3 and 2).
#include "cementsph/planning/PlanOutputs.h"
#include "cementsph/sph/Simulation.h"

#include <gtest/gtest.h>

using namespace cementsph;

namespace {

TEST(PlanOutputs, TheBestPlansSceneHasItsTipDirectionVolumeAndSecondTip) {
  planning::PlanRequest request;
  request.scene = scene::scenePreset("paper");
  request.direction = Eigen::Vector3d(0, 0, 2);
  planning::PlanResult plan;
  plan.best.tipMm = Eigen::Vector3d(1, 2, 3);
  plan.best.volumeMl = 2.5;
  plan.best.depthMm = 12;
  plan.best.secondTip = true;
  plan.best.secondDepthMm = 7;
  plan.best.secondVolumeMl = 1.0;
  const scene::SceneConfig s = planning::bestPlanScene(plan, request);
  EXPECT_EQ(*s.tipMm, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(s.direction, Eigen::Vector3d(0, 0, 1)); // normalised
  EXPECT_EQ(s.volumeMl, 2.5);
  ASSERT_TRUE(s.secondTipWithdrawalMm.has_value());
  EXPECT_EQ(*s.secondTipWithdrawalMm, 12.0 - 7.0);
  EXPECT_EQ(s.secondTipVolumeMl, 1.0);
  plan.best.secondTip = false;
  EXPECT_FALSE(planning::bestPlanScene(plan, request).secondTipWithdrawalMm.has_value());
}

TEST(PlanOutputs, TheTargetsVoxelsWithoutCementBecomeLabelThree) {
  scene::InjectionRunResult run;
  run.cementLabels = imaging::MaskType::New();
  imaging::MaskType::RegionType region;
  region.SetSize({9, 9, 9});
  run.cementLabels->SetRegions(region);
  run.cementLabels->Allocate();
  run.cementLabels->FillBuffer(0);
  run.cementLabels->SetPixel({4, 4, 4}, 1); // cement at the target's centre
  run.cementLabels->SetPixel({0, 0, 0}, 2); // a leak far from it
  const auto labels = planning::labelsWithUncoveredTarget(run, Eigen::Vector3d(4, 4, 4), 2.0);
  int three = 0;
  for (int k = 0; k < 9; ++k)
    for (int j = 0; j < 9; ++j)
      for (int i = 0; i < 9; ++i) three += labels->GetScalarComponentAsDouble(i, j, k, 0) == 3;
  EXPECT_EQ(three, 33 - 1);
  EXPECT_EQ(labels->GetScalarComponentAsDouble(4, 4, 4, 0), 1);
  EXPECT_EQ(labels->GetScalarComponentAsDouble(0, 0, 0, 0), 2);
  EXPECT_THROW(planning::labelsWithUncoveredTarget(scene::InjectionRunResult{}, Eigen::Vector3d(4, 4, 4), 2.0),
               std::runtime_error);
}

TEST(PlanOutputs, APlanWhoseInjectionsAllFailedIsAFailedRun) {
  planning::PlanResult plan;
  plan.evaluations.resize(2);
  plan.evaluations[0].failure = "tip in air";
  plan.evaluations[1].failure = "tip in air";
  EXPECT_THROW(planning::requireAnInjectionThatRan(plan), sph::SimulationError);
  plan.evaluations[1].failure.clear();
  EXPECT_NO_THROW(planning::requireAnInjectionThatRan(plan));
}

} // namespace
