// CT to porous solid on small synthetic volumes with exact expected counts (oracle: counting lattice points
// by hand, see docs/scene-figures.md), and the three input errors.
#include "cementsph/scene/PorousSolid.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

using namespace cementsph;
using namespace cementsph::scene;
using imaging::ImageType;

namespace {
// n^3 voxels of 1 mm at the origin; HU from f(i, j, k).
ImageType::Pointer volume(int n, const std::function<float(int, int, int)>& f, double spacingMm = 1.0) {
  auto img = ImageType::New();
  ImageType::RegionType region;
  ImageType::SizeType size;
  size.Fill(static_cast<itk::SizeValueType>(n));
  region.SetSize(size);
  img->SetRegions(region);
  img->SetSpacing(spacingMm);
  img->Allocate();
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) img->SetPixel({{i, j, k}}, f(i, j, k));
  return img;
}
// A solid slab z = 5..14 (1000 HU) in 20^3 voxels of 1 mm, air (-1000 HU) elsewhere; optionally a hole
// column through it at i = j = 10.
ImageType::Pointer slab(bool hole) {
  return volume(20, [hole](int i, int j, int k) {
    if (hole && i == 10 && j == 10) return -1000.f;
    return (k >= 5 && k <= 14) ? 1000.f : -1000.f;
  });
}
PorousSolidOptions options(double roiMm = 40.0) {
  PorousSolidOptions o;
  o.thresholdHu = 0;
  o.roiSizeMm = roiMm;
  o.reachMm = 2.5;
  o.restDensity = 1180;
  return o;
}
std::string errorOf(const ImageType* ct, const Eigen::Vector3d& tip, const PorousSolidOptions& o) {
  try {
    buildPorousSolid(ct, tip, o);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
} // namespace

TEST(PorousSolid, SlabKeepsOnlyTheLayersWithinReachOfPores) {
  const PorousSolid s = buildPorousSolid(slab(false), {10, 10, 2}, options());
  EXPECT_EQ(s.solidVoxels, 4000u); // 10 layers of 20 x 20
  // Reach 2.5 voxels: layers 5, 6 (pore at z = 4) and 13, 14 (pore at z = 15); layer 7 is 3 from the pores.
  EXPECT_EQ(s.keptVoxels, 1600u);
  EXPECT_EQ(s.positions.size(), 1600u);
  EXPECT_EQ(s.grid.size, (std::array<int, 3>{20, 20, 20}));
  EXPECT_EQ(s.connectedPoreVoxels, 5u * 400u); // below the slab only
  EXPECT_DOUBLE_EQ(s.particleMass, 1180 * 1e-9);
  EXPECT_NEAR(s.positions.front().z(), 5e-3, 1e-15); // voxel centres, metres
  EXPECT_NEAR(s.lowerM.x(), -0.5e-3, 1e-15);
  EXPECT_NEAR(s.upperM.z(), 19.5e-3, 1e-15);
}

TEST(PorousSolid, HoleThroughTheSlabKeepsTheVoxelsAroundIt) {
  const PorousSolid s = buildPorousSolid(slab(true), {10, 10, 2}, options());
  EXPECT_EQ(s.solidVoxels, 3990u);
  // 1600 - 4 hole voxels in the outer layers, + 6 inner layers x 20 voxels with 0 < a^2 + b^2 <= 6.25.
  EXPECT_EQ(s.keptVoxels, 1716u);
  EXPECT_EQ(s.connectedPoreVoxels, 8000u - 3990u); // the hole joins both sides
}

TEST(PorousSolid, RegionOfInterestIsACubeAboutTheTipClippedToTheCT) {
  // Tip (2, 2, 2), 10 mm: centres in [-3, 7] -> indices 0..7 (clipped at 0).
  const PorousSolid s = buildPorousSolid(slab(false), {2, 2, 2}, options(10));
  EXPECT_EQ(s.roiStart, (std::array<long, 3>{0, 0, 0}));
  EXPECT_EQ(s.roiSize, (std::array<long, 3>{8, 8, 8}));
  EXPECT_EQ(s.solidVoxels, 3u * 64u); // layers 5..7
  EXPECT_EQ(s.keptVoxels, 2u * 64u);  // layers 5, 6
  // Tip (15.2, 10, 2): x centres in [10.2, 20.2] -> 11..19; y 5..15; z 0..7.
  const PorousSolid t = buildPorousSolid(slab(false), {15.2, 10, 2}, options(10));
  EXPECT_EQ(t.roiStart, (std::array<long, 3>{11, 5, 0}));
  EXPECT_EQ(t.roiSize, (std::array<long, 3>{9, 11, 8}));
  EXPECT_NEAR(t.grid.origin.x(), 11e-3, 1e-15);
  EXPECT_EQ(t.solidVoxels, 3u * 99u);
}

TEST(PorousSolid, AnisotropicSpacingAndMass) {
  // 0.5 mm voxels: the slab layers 5..14 are at 2.5..7 mm; reach 2.5 mm = 5 voxels -> layers 5..9, 10..14 all
  // within reach of the pores at layers 4 and 15: everything is kept.
  const PorousSolid s = buildPorousSolid(volume(20, [](int, int, int k) { return (k >= 5 && k <= 14) ? 1000.f : -1000.f; }, 0.5),
                                         {5, 5, 1}, options());
  EXPECT_EQ(s.solidVoxels, 4000u);
  EXPECT_EQ(s.keptVoxels, 4000u);
  EXPECT_DOUBLE_EQ(s.particleMass, 1180 * 0.125e-9);
}

TEST(PorousSolid, TipOutsideTheCT) {
  const std::string e = errorOf(slab(false), {25, 10, 2}, options());
  EXPECT_NE(e.find("lies outside the CT"), std::string::npos) << e;
  EXPECT_NE(e.find("(25, 10, 2) mm"), std::string::npos) << e;
}

TEST(PorousSolid, TipInsideSolid) {
  const std::string e = errorOf(slab(false), {10, 10, 10}, options());
  EXPECT_NE(e.find("lies in solid"), std::string::npos) << e;
  EXPECT_NE(e.find("1000 HU"), std::string::npos) << e;
}

TEST(PorousSolid, NoPoreSpaceNearTheTip) {
  // A closed 2 x 2 x 2 cavity (8 mm^3) in solid: enough for 0.005 ml, not for 0.1 ml.
  auto ct = volume(12, [](int i, int j, int k) { return (i >= 5 && i <= 6 && j >= 5 && j <= 6 && k >= 5 && k <= 6) ? -1000.f : 1000.f; });
  PorousSolidOptions o = options();
  o.requiredPoreVolumeMm3 = 5;
  const PorousSolid s = buildPorousSolid(ct, {5, 5, 5}, o);
  EXPECT_EQ(s.connectedPoreVoxels, 8u);
  // Solid within 2.5 voxels of the cavity: count by brute force over the 12^3 grid.
  std::size_t expected = 0;
  for (int k = 0; k < 12; ++k)
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 12; ++i) {
        const bool pore = i >= 5 && i <= 6 && j >= 5 && j <= 6 && k >= 5 && k <= 6;
        if (pore) continue;
        bool near = false;
        for (int c = 5; c <= 6; ++c)
          for (int b = 5; b <= 6; ++b)
            for (int a = 5; a <= 6; ++a)
              near |= (i - a) * (i - a) + (j - b) * (j - b) + (k - c) * (k - c) <= 6;
        expected += near;
      }
  EXPECT_EQ(s.keptVoxels, expected);
  o.requiredPoreVolumeMm3 = 100;
  const std::string e = errorOf(ct, {5, 5, 5}, o);
  EXPECT_NE(e.find("no pore space near the tip"), std::string::npos) << e;
  EXPECT_NE(e.find("0.008 ml"), std::string::npos) << e;
}

TEST(PorousSolid, KeptVoxelsAgreeWithTestingEveryOffsetOnARandomMediumWithAnisotropicVoxels) {
  // Oracle: for every solid voxel, every pore voxel of the region tested by its distance (brute force, the
  // definition in PorousSolid.h); a pseudo-random medium of 95 % solid on 17 x 17 x 17 voxels of
  // 0.4 x 0.5 x 0.7 mm, reach 1.1 mm (2, 2 and 1 voxels along the axes), the tip voxel kept pore.
  const int n = 17;
  const double h[3] = {0.4, 0.5, 0.7};
  std::uint32_t state = 12345;
  std::vector<float> hu(std::size_t(n) * n * n);
  for (float& v : hu) {
    state = state * 1664525u + 1013904223u; // Numerical Recipes' LCG
    v = (state >> 8) % 100 < 95 ? 1000.f : -1000.f;
  }
  hu[8 + n * (8 + n * 8)] = -1000.f;
  auto img = ImageType::New();
  ImageType::RegionType region;
  ImageType::SizeType size;
  size.Fill(n);
  region.SetSize(size);
  img->SetRegions(region);
  ImageType::SpacingType spacing;
  for (unsigned a = 0; a < 3; ++a) spacing[a] = h[a];
  img->SetSpacing(spacing);
  img->Allocate();
  std::copy(hu.begin(), hu.end(), img->GetBufferPointer());
  PorousSolidOptions o = options();
  o.reachMm = 1.1;
  const PorousSolid s = buildPorousSolid(img, {8 * h[0], 8 * h[1], 8 * h[2]}, o);
  auto solidAt = [&](int i, int j, int k) { return hu[std::size_t(i + n * (j + n * k))] > 0; };
  std::size_t solid = 0, expected = 0;
  std::vector<Eigen::Vector3d> centres;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (!solidAt(i, j, k)) continue;
        ++solid;
        bool near = false;
        for (int c = 0; c < n && !near; ++c)
          for (int b = 0; b < n && !near; ++b)
            for (int a = 0; a < n && !near; ++a) {
              const double d2 = std::pow((a - i) * h[0], 2) + std::pow((b - j) * h[1], 2) + std::pow((c - k) * h[2], 2);
              near = !solidAt(a, b, c) && d2 <= 1.1 * 1.1 * (1 + 1e-12);
            }
        if (near) {
          ++expected;
          centres.emplace_back(i * h[0] * 1e-3, j * h[1] * 1e-3, k * h[2] * 1e-3);
        }
      }
  EXPECT_EQ(s.solidVoxels, solid);
  ASSERT_EQ(s.keptVoxels, expected);
  ASSERT_GT(expected, 0u);
  ASSERT_LT(expected, solid); // the medium has deep solid, so the reach matters
  for (std::size_t p = 0; p < centres.size(); ++p) EXPECT_LT((s.positions[p] - centres[p]).norm(), 1e-15) << p;
}

TEST(PorousSolid, ConnectedPoresAgreeWithABreadthFirstSearchOnRandomMedia) {
  // Oracle: a voxel-by-voxel breadth-first search over the 6 neighbours (written here, a queue of voxels), on
  // pseudo-random media of 35-65 % solid whose rows are shorter than, equal to, just over and several times a
  // 64-bit word (the search works on bit rows), with the tip in a corner and in the middle. Each case also counts
  // the solid voxels by hand.
  struct Case {
    int nx, ny, nz, solidPercent;
  };
  for (const Case& c : {Case{1, 9, 7, 40}, Case{5, 6, 7, 35}, Case{63, 5, 4, 45}, Case{64, 6, 5, 50},
                        Case{65, 7, 6, 55}, Case{130, 9, 8, 60}, Case{200, 12, 10, 65}, Case{129, 3, 3, 30}}) {
    std::uint32_t state = 777u + std::uint32_t(c.nx * 31 + c.ny);
    const std::size_t count = std::size_t(c.nx) * std::size_t(c.ny) * std::size_t(c.nz);
    std::vector<float> hu(count);
    for (float& v : hu) {
      state = state * 1664525u + 1013904223u; // Numerical Recipes' LCG
      v = int((state >> 8) % 100) < c.solidPercent ? 1000.f : -1000.f;
    }
    auto at = [&](int i, int j, int k) { return std::size_t(i) + std::size_t(c.nx) * (std::size_t(j) + std::size_t(c.ny) * std::size_t(k)); };
    for (const std::array<int, 3> tip : {std::array<int, 3>{0, 0, 0}, std::array<int, 3>{c.nx / 2, c.ny / 2, c.nz / 2}}) {
      std::vector<float> v = hu;
      v[at(tip[0], tip[1], tip[2])] = -1000.f; // the tip in pore space
      auto img = ImageType::New();
      ImageType::RegionType region;
      ImageType::SizeType size;
      size[0] = itk::SizeValueType(c.nx);
      size[1] = itk::SizeValueType(c.ny);
      size[2] = itk::SizeValueType(c.nz);
      region.SetSize(size);
      img->SetRegions(region);
      img->Allocate();
      std::copy(v.begin(), v.end(), img->GetBufferPointer());
      PorousSolidOptions o = options(1000.0); // the whole grid
      o.keptPositions = false;
      const PorousSolid s = buildPorousSolid(img, {double(tip[0]), double(tip[1]), double(tip[2])}, o);
      std::size_t solid = 0;
      for (float x : v) solid += x > 0;
      std::vector<char> seen(count, 0);
      std::vector<std::array<int, 3>> queue{tip};
      seen[at(tip[0], tip[1], tip[2])] = 1;
      for (std::size_t q = 0; q < queue.size(); ++q) {
        const auto p = queue[q];
        const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (const auto& e : d) {
          const int i = p[0] + e[0], j = p[1] + e[1], k = p[2] + e[2];
          if (i < 0 || j < 0 || k < 0 || i >= c.nx || j >= c.ny || k >= c.nz) continue;
          const std::size_t m = at(i, j, k);
          if (seen[m] || v[m] > 0) continue;
          seen[m] = 1;
          queue.push_back({i, j, k});
        }
      }
      const std::string where = std::to_string(c.nx) + " x " + std::to_string(c.ny) + " x " + std::to_string(c.nz) +
                                ", tip (" + std::to_string(tip[0]) + ", " + std::to_string(tip[1]) + ", " + std::to_string(tip[2]) + ")";
      EXPECT_EQ(s.solidVoxels, solid) << where;
      EXPECT_EQ(s.connectedPoreVoxels, queue.size()) << where;
      ASSERT_EQ(s.solid.size(), count) << where;
      for (std::size_t m = 0; m < count; ++m) ASSERT_EQ(s.solid[m], v[m] > 0 ? 1 : 0) << where << ", voxel " << m;
    }
  }
}

TEST(PorousSolid, TheThresholdIsTheDoubleComparisonAtTheFloatsNextToIt) {
  // HU are floats and threshold_hu a double: a voxel is solid when its value, as a double, is above the threshold
  // (the definition), checked at the floats on either side of thresholds that a float can and cannot hold.
  for (const double threshold : {0.1, 0.5, -250.3, 1e-30, 400.0}) {
    const float at = float(threshold);
    const float values[4] = {std::nextafter(at, -1e30f), at, std::nextafter(at, 1e30f), -1000.f};
    auto ct = volume(4, [&](int i, int, int) { return values[(i + 3) % 4]; }); // i = 0: -1000 HU, the tip's
    PorousSolidOptions o = options();
    o.thresholdHu = threshold;
    const PorousSolid s = buildPorousSolid(ct, {0, 0, 0}, o);
    for (int i = 1; i < 4; ++i) {
      const bool solid = double(values[i - 1]) > threshold;
      EXPECT_EQ(s.solid[s.grid.index(i, 2, 1)], solid ? 1 : 0) << "threshold " << threshold << ", value " << values[i - 1];
    }
  }
}
