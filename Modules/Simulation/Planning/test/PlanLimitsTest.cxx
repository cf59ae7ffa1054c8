// Plans that make sense (issue 20 item 5), on the vertebra phantom: cement that reaches the region's edge makes
// an evaluation a warning and outside the limits, costing 5 in the objective (InjectionPlanner.h). The oracle is
// the objective's formula (InjectionPlanner.h's header) applied to each evaluation's own coverage, volume,
// pressure and leak: with the edge warning it is 5 below planObjective, without it equal. A region of 12 mm
// around the tip cannot hold 2 ml (12^3 mm^3 of bone at the phantom's porosity is under 1.7 ml), so the edge is
// reached; PlanTest's plan (40 mm region) never reaches it.
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/phantom/VertebraPhantom.h"
#include "cementsph/planning/InjectionPlanner.h"
#include "cementsph/planning/PlanOutputs.h"

#include <vtkDataArray.h>
#include <vtkPointData.h>

#include <gtest/gtest.h>

#include <filesystem>

namespace {
using namespace cementsph;

TEST(PlanLimits, CementAtTheRegionsEdgeIsAWarningAndAPlanLimit) {
  const auto ct = imaging::readVolume(
      (std::filesystem::path(CEMENTSPH_TEST_DATA_DIR) / "vertebra-phantom" / "pre.nrrd").string());
  planning::PlanRequest r;
  r.scene = scene::scenePreset("paper");
  r.scene.roiSizeMm = 12;
  r.entryMm = Eigen::Vector3d(48.5, 52.4, 22.5); // transpedicular (PlanTrajectoryTest)
  r.targetCentreMm = Eigen::Vector3d(32, 21, 22.5);
  r.direction = r.targetCentreMm - r.entryMm;
  r.minDepthMm = 25;
  r.maxDepthMm = r.direction.norm();
  r.minVolumeMl = 1.5;
  r.maxVolumeMl = 2;
  r.maxLeakageMl = 1; // the leak limit out of the way: only the edge limits
  r.maxEvaluations = 6;
  r.starts = 1;
  const planning::PlanResult plan = planning::planInjection(ct, r);
  std::size_t atEdge = 0;
  for (const auto& e : plan.evaluations) {
    if (!e.failure.empty()) continue;
    const double formula = planning::planObjective(r, e.coverage, e.volumeMl, e.syringeMpa, e.leakageMl);
    if (e.warnings.empty()) {
      EXPECT_DOUBLE_EQ(e.objective, formula);
      continue;
    }
    ++atEdge;
    EXPECT_NE(e.warnings.front().find("reached the edge"), std::string::npos) << e.warnings.front();
    EXPECT_FALSE(e.withinLimits);
    EXPECT_DOUBLE_EQ(e.objective, formula - 5.0);
    EXPECT_NE(e.toJson().at("warnings").dump().find("edge"), std::string::npos);
  }
  EXPECT_GT(atEdge, 0u) << "no evaluation reached the 12 mm region's edge";
}

// The leak limit counts leakage as the anatomy does (item 1): marrow fat inside the body (-30 HU, below the bone
// band) is bone, not a leak. The anatomy variant with a 5 mm sphere of fat (VertebraPhantom.h: centred 7 mm left,
// 3 mm anterior, 2 mm superior of the body's centre) and the target on it, no leakage allowed: the best plan is
// within the limits with no leak, and its injection (run again from bestPlanScene) put cement into the fat
// sphere's voxels (the oracle: the cement points inside the analytic sphere, grown by nothing), which the HU
// rule would have counted as leaked.
TEST(PlanLimits, MarrowFatIsNotLeakageForTheLeakLimit) {
  phantom::VertebraOptions o;
  o.marrowFatRadiusMm = 5;
  const phantom::VertebraResult v = phantom::makeVertebra(o);
  const Eigen::Vector3d fat(v.marrowFatCentreMm[0], v.marrowFatCentreMm[1], v.marrowFatCentreMm[2]);
  planning::PlanRequest r;
  r.scene = scene::scenePreset("paper");
  r.entryMm = Eigen::Vector3d(48.5, 52.4, 22.5); // transpedicular (PlanTrajectoryTest): clear of the canal
  r.targetCentreMm = fat;
  r.direction = r.targetCentreMm - r.entryMm;
  r.minDepthMm = 20;
  r.maxDepthMm = r.direction.norm();
  r.targetRadiusMm = 5;
  r.minVolumeMl = 1;
  r.maxVolumeMl = 2;
  r.maxLeakageMl = 0;
  r.maxEvaluations = 8;
  r.starts = 1;
  const planning::PlanResult plan = planning::planInjection(v.ct, r);
  ASSERT_TRUE(plan.best.failure.empty()) << plan.best.failure;
  EXPECT_TRUE(plan.best.withinLimits);
  EXPECT_DOUBLE_EQ(plan.best.leakageMl, 0.0);
  const auto run = scene::runInjection(v.ct, planning::bestPlanScene(plan, r), {});
  vtkDataArray* volume = run.particles->GetPointData()->GetArray("cement_volume_mm3");
  ASSERT_NE(volume, nullptr);
  double inFatMm3 = 0;
  for (vtkIdType i = 0; i < run.particles->GetNumberOfPoints(); ++i) {
    const double* p = run.particles->GetPoint(i);
    if ((Eigen::Vector3d(p[0], p[1], p[2]) - fat).norm() <= o.marrowFatRadiusMm) inFatMm3 += volume->GetTuple1(i);
  }
  EXPECT_GT(inFatMm3, 50.0) << "the cement did not reach the fat: the test shows nothing";
  EXPECT_DOUBLE_EQ(run.summary.leakageVolumeMl, 0.0);
}

} // namespace
