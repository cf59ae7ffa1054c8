// plan returns the smallest volume that covers the target on the vertebra phantom (issue 20, "Done when"), checked
// by exhaustive search. PlanSmallestVolumeTest has the analytic curve of a uniform block; a vertebra has none, so
// here the oracle is computed independently of the planner's search: the injection driver (runInjection, not the
// planner's filter and not its BOBYQA or bisection) run at the plan's depth for every volume on a 0.05 ml grid
// from the request's smallest volume up to the search's best, each coverage measured with targetCoverage (its own
// test: Plan.CoverageIsTheTargetsVolumeFraction). The smallest grid volume whose coverage keeps within the trim's
// tolerance of the search's best and within the limits is what the plan should return.
// Tolerances: the bisection stops at 0.05 ml (BOBYQA's volume xtol) and the grid is 0.05 ml, so the plan may lie
// one grid step above the smallest; below it only if the curve is not monotone (the plan must then keep its
// coverage, which is asserted directly).
#include "cementsph/planning/InjectionPlanner.h"
#include "cementsph/scene/InjectionRunner.h"
#include "VertebraPlanRequest.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace {
using namespace cementsph;
using planning::testing::transpedicularRequest;
using planning::testing::vertebraPhantomCt;

struct Swept {
  double volumeMl, coverage, syringeMpa, leakageMl;
  bool edge;
};

} // namespace

TEST(PlanSmallestVolumeVertebra, ThePlansVolumeIsTheSmallestThatKeepsTheCoverageByExhaustiveSearch) {
  const auto ct = vertebraPhantomCt();
  planning::PlanRequest r = transpedicularRequest();
  r.minDepthMm = 10;
  r.maxDepthMm = 36;
  r.targetRadiusMm = 6;
  r.minVolumeMl = 1;
  r.maxVolumeMl = 4;
  r.maxSyringeMpa = 3;
  r.maxLeakageMl = 0;
  const planning::PlanResult plan = planning::planInjection(ct.GetPointer(), r);
  ASSERT_TRUE(plan.best.failure.empty()) << plan.best.failure;
  ASSERT_TRUE(plan.searchBest.withinLimits);
  const double wanted = plan.searchBest.coverage - r.trimCoverageTolerance;
  std::printf("search best %.4f ml at %.3f mm, coverage %.4f; plan %.4f ml, coverage %.4f\n", plan.searchBest.volumeMl,
              plan.searchBest.depthMm, plan.searchBest.coverage, plan.best.volumeMl, plan.best.coverage);

  // The sweep, through the driver at the plan's depth and the planner's scene changes (InjectionPlanner.cpp).
  const Eigen::Vector3d axis = r.direction.normalized();
  std::vector<Swept> sweep;
  double smallest = -1;
  for (int k = 0;; ++k) {
    const double volumeMl = r.minVolumeMl + 0.05 * k;
    if (volumeMl > plan.searchBest.volumeMl + 1e-9) break;
    scene::SceneConfig s = r.scene;
    s.tipMm = r.entryMm + plan.searchBest.depthMm * axis;
    s.direction = axis;
    s.explicitKeys.insert("direction");
    s.volumeMl = volumeMl;
    s.snapshotIntervalS = 1e9;
    scene::InjectionRunOptions options;
    const scene::InjectionRunResult run = scene::runInjection(ct.GetPointer(), s, options);
    bool edge = false;
    for (const std::string& w : run.summary.warnings) edge = edge || w.find("reached the edge") != std::string::npos;
    const Swept e{volumeMl, planning::targetCoverage(run.particles, r.targetCentreMm, r.targetRadiusMm),
                  run.summary.maxInjectionPressurePa * 1e-6, run.summary.leakageVolumeMl, edge};
    sweep.push_back(e);
    const bool keeps = e.coverage >= wanted && e.syringeMpa <= r.maxSyringeMpa && e.leakageMl <= r.maxLeakageMl && !edge;
    std::printf("  %.2f ml: coverage %.4f, syringe %.3f MPa, leak %.4f ml%s\n", volumeMl, e.coverage, e.syringeMpa,
                e.leakageMl, keeps ? "  keeps" : "");
    if (keeps && smallest < 0) smallest = volumeMl;
  }
  ASSERT_GT(smallest, 0) << "no volume up to the search's best keeps its coverage: the sweep contradicts the search";
  std::printf("smallest keeping volume by exhaustive search: %.2f ml\n", smallest);
  // The plan keeps the coverage and the limits itself ...
  EXPECT_GE(plan.best.coverage, wanted - 1e-12);
  EXPECT_TRUE(plan.best.withinLimits);
  // ... and spends at most one grid step more than the smallest volume that does.
  EXPECT_LE(plan.best.volumeMl, smallest + 0.05 + 1e-9);
  EXPECT_GE(plan.best.volumeMl, r.minVolumeMl - 1e-9);
}
