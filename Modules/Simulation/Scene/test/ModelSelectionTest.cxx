// pressure_model "auto" between particles and voxels (ModelSelection.h, issue 19 item 3), on media whose pore
// scale is counted here by hand:
//  * a slab medium: solid planes `rod` voxels thick every `period` voxels along z, pore elsewhere. Along z the
//    pore runs are period - rod voxels; along x and y a line is all solid (in a plane) or all pore (n voxels,
//    one run). The mean pore chord L = (pore length over all lines) / (runs over all lines) follows in closed
//    form (below), and poreScaleOf must give it to round-off; single pore voxels in solid: L = one voxel;
//  * the choice: resolved pore space (L >= 3 voxels, L >= 8 particle spacings, pore-resolved) -> particle-darcy;
//    the same medium as a continuum (clinical CT) -> voxel-darcy; particles too coarse for the pores ->
//    voxel-darcy; pores of 1 voxel (under 3) -> voxel-darcy; the paper preset -> its equation of state.
// Creeping flow throughout (the default preset's rho0 1180 kg/m^3 and cs 1 m/s: Re, St << 0.1, compression > 1).
#include "cementsph/scene/ModelSelection.h"
#include "cementsph/scene/SceneConfig.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

using namespace cementsph::scene;

namespace {
constexpr double kRho0 = 1180.0, kSoundSpeed = 1.0;

struct Slabs {
  int n, period, rod;
  double spacingM;
  std::vector<std::uint8_t> solid() const {
    std::vector<std::uint8_t> s(std::size_t(n) * n * n);
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) s[std::size_t(i + n * (j + n * k))] = k % period < rod;
    return s;
  }
  // Closed form, n a multiple of period: planes of pore voxels per period (period - rod), n / period periods.
  double meanChordM() const {
    const double porePlanes = double(n / period) * (period - rod);
    const double zLength = double(n) * n * porePlanes, zRuns = double(n) * n * (n / period);
    const double xyLength = 2.0 * n * porePlanes * n, xyRuns = 2.0 * n * porePlanes;
    return (zLength + xyLength) / (zRuns + xyRuns) * spacingM;
  }
  PoreScale scale(bool poreResolved) const {
    return poreScaleOf(solid(), {n, n, n}, {spacingM, spacingM, spacingM}, poreResolved);
  }
};

SceneConfig sceneWithRadius(double particleRadiusMm, const std::string& preset = "default") {
  nlohmann::json j{{"tip_mm", {5, 5, 5}}, {"particle_radius_mm", particleRadiusMm}};
  if (preset == "paper") j["preset"] = "paper";
  return sceneFromJson(j);
}
} // namespace

TEST(ModelSelection, TheMeanPoreChordIsTheHandCount) {
  const Slabs wide{40, 20, 3, 0.5e-3}, narrow{40, 4, 2, 0.5e-3};
  EXPECT_NEAR(wide.scale(true).meanPoreChordM, wide.meanChordM(), 1e-12);
  EXPECT_NEAR(narrow.scale(true).meanPoreChordM, narrow.meanChordM(), 1e-12);
  EXPECT_DOUBLE_EQ(wide.scale(true).voxelSizeM, 0.5e-3);
  // All pore: one run per line, L = the region's extent (open space).
  const std::vector<std::uint8_t> open(8 * 8 * 8, 0);
  EXPECT_NEAR(poreScaleOf(open, {8, 8, 8}, {1e-3, 1e-3, 1e-3}, true).meanPoreChordM, 8e-3, 1e-15);
}

// Each axis counted apart (the slabs above are the same along x and y, so a count that mixed those two axes
// passed them): solid planes normal to y (every j divisible by 4) in a 12 x 12 x 12 region, spacings 1, 2 and
// 0.5 mm. By hand: 9 pore planes, 1296 pore voxels; runs along x 9 x 12 = 108 (whole rows), along z 108, along y
// 3 per (i, k) column = 432; L = 1296 x (1 + 2 + 0.5) mm / 648 = 7 mm.
TEST(ModelSelection, EachAxisRunsAreCountedAlongThatAxis) {
  const int n = 12;
  std::vector<std::uint8_t> solid(std::size_t(n * n * n), 0);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; j += 4)
      for (int i = 0; i < n; ++i) solid[std::size_t(i + n * (j + n * k))] = 1;
  EXPECT_NEAR(poreScaleOf(solid, {n, n, n}, {1e-3, 2e-3, 0.5e-3}, true).meanPoreChordM, 7e-3, 1e-15);
}

TEST(ModelSelection, ResolvedPoreSpaceRunsParticlesAndClinicalCtRunsVoxels) {
  const Slabs wide{40, 20, 3, 0.5e-3}; // L = 13.5 mm by hand (27 voxels)
  const double L = wide.meanChordM();
  ASSERT_GT(L, 3 * 0.5e-3);
  // d = 0.6 mm: L / d = 22 >= 8, L = 27 voxels >= 3: particles.
  const ModelChoice fine = chooseModel(sceneWithRadius(0.3), kRho0, kSoundSpeed, 0.85, wide.scale(true));
  EXPECT_EQ(fine.pressureModel, "particle-darcy") << fine.reason;
  EXPECT_NE(fine.reason.find("resolved pore space"), std::string::npos) << fine.reason;
  EXPECT_NEAR(fine.numbers.particlesAcrossPore, L / 0.6e-3, 1e-9);
  // The same CT read as a continuum (clinical CT, bone from HU): voxels.
  const ModelChoice clinical = chooseModel(sceneWithRadius(0.3), kRho0, kSoundSpeed, 0.85, wide.scale(false));
  EXPECT_EQ(clinical.pressureModel, "voxel-darcy") << clinical.reason;
  // No pore scale given (the run estimate's call): voxels, as before.
  EXPECT_EQ(chooseModel(sceneWithRadius(0.3), kRho0, kSoundSpeed, 0.85).pressureModel, "voxel-darcy");
  // Particles of d = 2 mm: L / d = 6.75 < 8, they do not resolve the pores: voxels, and the reason says why.
  const ModelChoice coarse = chooseModel(sceneWithRadius(1.0), kRho0, kSoundSpeed, 0.85, wide.scale(true));
  EXPECT_EQ(coarse.pressureModel, "voxel-darcy") << coarse.reason;
  EXPECT_NE(coarse.reason.find("particles (particle-darcy) need 8 spacings"), std::string::npos) << coarse.reason;
  // The paper preset keeps the paper's model.
  const ModelChoice paper = chooseModel(sceneWithRadius(0.3, "paper"), kRho0, kSoundSpeed, 0.85, wide.scale(true));
  EXPECT_EQ(paper.pressureModel, "equation-of-state") << paper.reason;
}

TEST(ModelSelection, PoresTheCtDoesNotResolveRunVoxels) {
  // Single pore voxels every second voxel along each axis, solid between: every pore run is one voxel, L = 0.5 mm.
  const int n = 20;
  std::vector<std::uint8_t> solid(std::size_t(n) * n * n, 1);
  for (int k = 0; k < n; k += 2)
    for (int j = 0; j < n; j += 2)
      for (int i = 0; i < n; i += 2) solid[std::size_t(i + n * (j + n * k))] = 0;
  const PoreScale scale = poreScaleOf(solid, {n, n, n}, {0.5e-3, 0.5e-3, 0.5e-3}, true);
  EXPECT_NEAR(scale.meanPoreChordM, 0.5e-3, 1e-15);
  // Particles fine enough for the pores (d = 0.02 mm, 25 across) do not make a 1-voxel pore resolved.
  const ModelChoice c = chooseModel(sceneWithRadius(0.01), kRho0, kSoundSpeed, 0.125, scale);
  EXPECT_EQ(c.pressureModel, "voxel-darcy") << c.reason;
  EXPECT_NE(c.reason.find("the CT does not resolve the pores"), std::string::npos) << c.reason;
}
