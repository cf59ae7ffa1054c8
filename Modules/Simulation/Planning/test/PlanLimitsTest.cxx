// Plans that make sense (issue 20 item 5), on the vertebra phantom: cement that reaches the region's edge makes
// an evaluation a warning and outside the limits, costing 5 in the objective (InjectionPlanner.h). The oracle is
// the objective's formula (InjectionPlanner.h's header) applied to each evaluation's own coverage, volume,
// pressure and leak: with the edge warning it is 5 below planObjective, without it equal. A region of 12 mm
// around the tip cannot hold 2 ml (12^3 mm^3 of bone at the phantom's porosity is under 1.7 ml), so the edge is
// reached; PlanTest's plan (40 mm region) never reaches it.
#include "cementsph/planning/InjectionPlanner.h"
#include "cementsph/imaging/VolumeIO.h"

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

} // namespace
