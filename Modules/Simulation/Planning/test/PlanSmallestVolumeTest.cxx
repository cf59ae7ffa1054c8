// `plan` returns the smallest volume that covers the target (issue 20, "Done when"), where the coverage-versus-
// volume curve is known without the code: a uniform block of continuum bone (150 HU inside a 1 mm cortical
// shell, 0.5 mm voxels) and a target ball of radius a = 8 mm centred on the trajectory. In a uniform medium the
// Darcy filling from a point source is a ball that fills the pore space, radius R = (3 V / (4 pi phi))^(1/3), so
// the covered fraction of a target ball about the tip is
//     coverage(V) = min(1, V / V*),   V* = phi (4/3) pi a^3,
// phi = 1 - 150 / 1400 (the calibration's porosity, as CapillaryLeakTest writes it out). The objective
// coverage - c V (InjectionPlanner.h, c = 0.01 per ml) rises with slope 1 / V* - c > 0 below V* and falls with
// slope -c above it: its maximum is at V*, the smallest volume with full coverage. Tolerances: the front is a
// voxel layer, so R is known to half a voxel (0.25 mm), i.e. V to 3 x 0.25 / 8 = 9.4 %, plus BOBYQA's volume
// xtol 0.05 ml: the plan's volume within 10 % of V* + 0.05 ml; each evaluation's coverage against the curve
// at its own volume and tip, within 0.1 (the half-voxel shell at the front and the voxelised target ball).
// The search alone stops short of V* (measured 2026-12-03 before the volume trim: 2.375 ml, below); the planner's
// volume trim (InjectionPlanner.h) bisects the volume at the best depth for the smallest keeping the coverage
// within 0.01, so the plan's volume is V* less at most 0.01 V* (coverage = V / V* below V*) and the 0.05 ml
// resolution: inside the tolerance above.
#include "cementsph/planning/InjectionPlanner.h"

#include <gtest/gtest.h>

#include <itkImage.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace {
using namespace cementsph;

constexpr double kPi = 3.14159265358979323846;
constexpr int kVoxels = 64;         // 32 mm at 0.5 mm
constexpr double kSpacingMm = 0.5;
constexpr double kBoneHu = 150;

imaging::ImageType::Pointer uniformBlock() {
  auto img = imaging::ImageType::New();
  imaging::ImageType::RegionType region;
  imaging::ImageType::SizeType size;
  size.Fill(kVoxels);
  region.SetSize(size);
  img->SetRegions(region);
  img->SetSpacing(kSpacingMm);
  img->Allocate();
  for (int k = 0; k < kVoxels; ++k)
    for (int j = 0; j < kVoxels; ++j)
      for (int i = 0; i < kVoxels; ++i) {
        const bool shell = std::min({i, j, k}) < 2 || std::max({i, j, k}) > kVoxels - 3;
        img->SetPixel({{i, j, k}}, shell ? 1000.f : float(kBoneHu));
      }
  return img;
}

// The covered fraction of a ball of radius a about c by a cement ball of radius R about the tip t (the volume
// of the two balls' lens over the target's), d = |t - c|.
double ballCoverage(double R, double a, double d) {
  if (d + a <= R) return 1.0;
  if (d >= R + a) return 0.0;
  if (d + R <= a) return std::pow(R / a, 3);
  const double lens = kPi * std::pow(R + a - d, 2) * (d * d + 2 * d * a - 3 * a * a + 2 * d * R + 6 * a * R - 3 * R * R) /
                      (12 * d);
  return lens / (4.0 / 3.0 * kPi * a * a * a);
}

struct Plan {
  double phi = 1 - kBoneHu / 1400.0, a = 8;
  double smallestMl = phi * 4.0 / 3.0 * kPi * a * a * a * 1e-3; // V*, 1.915 ml
  planning::PlanRequest request;
  planning::PlanResult result;
  Plan() {
    planning::PlanRequest& r = request;
    // tip_mm and volume_ml are the plan's to choose; the scene needs them to parse.
    r.scene = scene::sceneFromJson({{"tip_mm", {16, 16, 16}},
                                    {"volume_ml", 1},
                                    {"cannula_wall", false},
                                    {"flow_rate_ml_per_s", 0.05},
                                    {"viscosity_pa_s", 100},
                                    {"bone_model", "continuum"}});
    r.entryMm = Eigen::Vector3d(16, 16, 2);
    r.direction = Eigen::Vector3d::UnitZ();
    r.targetCentreMm = Eigen::Vector3d(16, 16, 16); // depth 14 mm
    r.targetRadiusMm = a;
    r.minDepthMm = 12;
    r.maxDepthMm = 16;
    r.minVolumeMl = 0.5;
    r.maxVolumeMl = 3; // R 9.3 mm: inside the block's 15 mm half-width
    r.maxLeakageMl = 0;
    r.maxEvaluations = 16;
    r.starts = 1;
    result = planning::planInjection(uniformBlock(), r);
    std::printf("V* = %.4f ml; plan: %.4f ml at depth %.3f mm, coverage %.4f, objective %.4f (%zu evaluations, %s)\n",
                smallestMl, result.best.volumeMl, result.best.depthMm, result.best.coverage, result.best.objective,
                result.evaluations.size(), result.stopReason.c_str());
  }
};

const Plan& plan() {
  static const Plan p;
  return p;
}

} // namespace

// The curve itself: every evaluation's coverage is the two balls' at its own volume and tip.
TEST(PlanSmallestVolume, EachEvaluationsCoverageIsTheDarcyBallsInAUniformBlock) {
  const Plan& p = plan();
  ASSERT_TRUE(p.result.best.failure.empty()) << p.result.best.failure;
  for (const auto& e : p.result.evaluations) {
    ASSERT_TRUE(e.failure.empty()) << e.failure;
    const double R = std::cbrt(3 * e.volumeMl * 1e3 / (4 * kPi * p.phi));
    const double expected = ballCoverage(R, p.a, (e.tipMm - p.request.targetCentreMm).norm());
    std::printf("  %.4f ml at depth %.3f mm: coverage %.4f, the balls' %.4f\n", e.volumeMl, e.depthMm, e.coverage,
                expected);
    EXPECT_NEAR(e.coverage, expected, 0.1) << e.volumeMl << " ml at depth " << e.depthMm << " mm";
    EXPECT_TRUE(e.warnings.empty()) << e.warnings.front();
  }
}

// Measured 2026-12-03: the search alone returned 2.375 ml (coverage 0.9953, objective 0.9716) against V* = 1.915 ml:
// BOBYQA ended ("success": its trust region shrank to the 0.05 ml xtol) after 7 of 16 evaluations (3.0, 2.375,
// 1.75, 2.64, 2.48 ml at the centre's depth), its quadratic model of a curve with a knee at V* never trying
// 1.8-2.3 ml. With the volume trim: 1.906 ml (coverage 0.9902) after 7 more injections. The search's own best is
// kept as searchBest and must be no smaller than the plan.
TEST(PlanSmallestVolume, ThePlansVolumeIsTheSmallestThatCoversTheTarget) {
  const Plan& p = plan();
  ASSERT_TRUE(p.result.best.failure.empty()) << p.result.best.failure;
  EXPECT_NEAR(p.result.best.volumeMl, p.smallestMl, 0.1 * p.smallestMl + 0.05);
  EXPECT_GE(p.result.best.coverage, 0.9);
  EXPECT_TRUE(p.result.best.withinLimits);
  EXPECT_LE(p.result.best.volumeMl, p.result.searchBest.volumeMl);
  EXPECT_GE(p.result.best.coverage, p.result.searchBest.coverage - p.request.trimCoverageTolerance);
}
