// RunEstimate against hand-computed counts (oracles in the comments), and the limits' messages.
#include "cementsph/scene/RunEstimate.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using namespace cementsph::scene;

SceneConfig scene(double radiusMm) {
  SceneConfig s;
  s.tipMm = Eigen::Vector3d(0, 0, 0);
  s.particleRadiusMm = radiusMm;
  s.volumeMl = 1.0;
  s.cannulaWall = false;
  return s;
}

TEST(RunEstimate, FluidCountIsTheVolumeOverTheCubedSpacing) {
  // r 0.5 mm: d = 1 mm, 1 ml = 1000 mm^3 -> 1000 particles exactly.
  EXPECT_NEAR(estimateRun(scene(0.5)).fluidParticles, 1000.0, 1e-9);
  // Solid bound: a 40 mm cube of 0.5 mm^3 voxels -> 64000 / 0.5 = 128000.
  EXPECT_NEAR(estimateRun(scene(0.5), 0.5).solidParticlesMax, 128000.0, 1e-6);
}

TEST(RunEstimate, AMicrometreRadiusIsRefusedNamingTheKey) {
  // r 1e-6 mm: 1000 / (2e-6)^3 = 1.25e20 particles, far past any memory.
  const RunEstimate e = estimateRun(scene(1e-6));
  EXPECT_NEAR(e.fluidParticles / 1.25e20, 1.0, 1e-9);
  try {
    checkRunSize(e, true);
    FAIL() << "not refused";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("particle_radius_mm"), std::string::npos) << error.what();
  }
}

TEST(RunEstimate, TinyDisplacementLimitIsRefusedUnlessAllowed) {
  SceneConfig s = scene(0.57);
  s.integrator = "overdamped";
  s.maxDisplacementOverH = 1e-9;
  // Exit speed Q/A = 50 mm^3/s / (pi 1.194^2 mm^2) = 11.16 mm/s over 20 s = 223 mm; a step moves at most
  // 1e-9 h (h = d = 1.14 mm in the default preset): 1.96e11 steps.
  const RunEstimate e = estimateRun(s);
  EXPECT_NEAR(e.steps / 1.96e11, 1.0, 0.01);
  EXPECT_EQ(e.drivingKey, "max_displacement_over_h");
  EXPECT_THROW(checkRunSize(e, false), std::invalid_argument);
  EXPECT_NO_THROW(checkRunSize(e, true));
}

TEST(RunEstimate, TheVoxelGridDefaultIsEstimatedByItsVoxels) {
  // The default scene is creeping flow: auto runs the voxel-grid Darcy filling. A 40 mm cube of 0.5 mm^3
  // voxels: 128000 voxels; 1 ml fills at least 1000 / 0.5 = 2000 of them. (The bytes per voxel are checked
  // against a measured peak in RunEstimateMemoryTest, not against the estimator's own constant here.)
  const RunEstimate e = estimateRun(scene(0.5), 0.5);
  ASSERT_TRUE(e.voxelDarcy);
  EXPECT_NEAR(e.voxels, 128000.0, 1e-6);
  EXPECT_NEAR(e.cementVoxels, 2000.0, 1e-9);
  EXPECT_EQ(checkRunSize(e, false), ""); // seconds, not worth a note
  // 200 ml is long in particle steps (1.6e5 particles emitted one per step) but not for the voxel model.
  SceneConfig big = scene(0.57);
  big.volumeMl = 200;
  EXPECT_NO_THROW(checkRunSize(estimateRun(big, 0.1), false));
  big.pressureModel = "equation-of-state";
  EXPECT_THROW(checkRunSize(estimateRun(big, 0.1), false), std::invalid_argument);
}

} // namespace
