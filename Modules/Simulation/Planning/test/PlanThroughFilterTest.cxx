// plan's evaluations run through vtkSPHInjectionFilter without its image outputs (ProduceImageOutputs off,
// issue 24). The oracle: the inject driver itself (runInjection, InjectionRunner.h) run directly on the same CT
// with each evaluation's scene (the trajectory's tip and direction, the evaluation's volume, one snapshot), its
// figures read independently of the planner: the coverage of its cement points (targetCoverage), its largest
// syringe pressure and its leak. Both are the one driver on the same voxels, so the figures must be identical to
// the bit (EXPECT_EQ on doubles, no tolerance), and each objective must be the header's formula of them.
#include "VertebraPlanRequest.h"

#include "cementsph/planning/InjectionPlanner.h"
#include "cementsph/scene/InjectionRunner.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {
using namespace cementsph;

TEST(PlanThroughFilter, EvaluationsEqualTheDriversRunsOnTheSameScenes) {
  const auto ct = planning::testing::vertebraPhantomCt();
  planning::PlanRequest r = planning::testing::transpedicularRequest();
  r.minDepthMm = 25;
  r.minVolumeMl = 0.3;
  r.maxVolumeMl = 0.6;
  r.maxEvaluations = 6; // BOBYQA's first 2n + 1 = 5 and one more
  r.starts = 1;
  const planning::PlanResult plan = planning::planInjection(ct, r);
  ASSERT_FALSE(plan.evaluations.empty());
  std::size_t compared = 0;
  for (const planning::PlanEvaluation& e : plan.evaluations) {
    SCOPED_TRACE("evaluation " + std::to_string(e.index) + " at depth " + std::to_string(e.depthMm) + " mm, " +
                 std::to_string(e.volumeMl) + " ml");
    ASSERT_TRUE(e.failure.empty()) << e.failure;
    scene::SceneConfig s = r.scene;
    s.tipMm = e.tipMm;
    s.direction = r.direction.normalized();
    s.explicitKeys.insert("direction");
    s.volumeMl = e.volumeMl;
    s.snapshotIntervalS = 1e9;
    const scene::InjectionRunResult direct = scene::runInjection(ct, s, {});
    const double coverage = planning::targetCoverage(direct.particles, r.targetCentreMm, r.targetRadiusMm);
    EXPECT_EQ(e.coverage, coverage);
    EXPECT_EQ(e.syringeMpa, direct.summary.maxInjectionPressurePa * 1e-6);
    EXPECT_EQ(e.leakageMl, direct.summary.leakageVolumeMl);
    std::vector<std::string> atEdge;
    for (const std::string& w : direct.summary.warnings)
      if (w.find("reached the edge") != std::string::npos) atEdge.push_back(w);
    EXPECT_EQ(e.warnings, atEdge);
    const double formula = planning::planObjective(r, coverage, e.volumeMl, e.syringeMpa, e.leakageMl);
    EXPECT_EQ(e.objective, e.warnings.empty() ? formula : formula - 5.0);
    ++compared;
  }
  EXPECT_GT(plan.best.coverage, 0.0) << "no cement reached the target: the comparison shows little";
  EXPECT_EQ(compared, plan.evaluations.size());
}

} // namespace
