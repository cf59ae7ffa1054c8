// Cement segmentation on synthetic pre/post pairs: the component at the injection point (not the
// largest bright region) is kept, volume in ml, closing, and honest zeros when there is no cement.
#include "SyntheticVolumes.h"
#include "cementsph/imaging/CementSegmentation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <random>

using namespace cementsph::imaging;
using namespace cementsph::testing;

namespace {

struct Pair {
  Grid grid;
  ImageType::Pointer pre, post;
  Vec3 cement{}, leak{};
  double cementRadius = 6.0, leakRadius = 8.0;
};

// Cement (r = 6 mm) at the injection site and a larger bright region (r = 8 mm) elsewhere.
Pair makePair() {
  Pair p;
  p.grid.size = {56, 56, 48};
  p.grid.spacing = {1.0, 1.0, 1.0};
  p.grid.origin = {-27.5, -27.5, -23.5};
  const BonePhantom phantom({0, 0, 0}, {25, 25, 21});
  p.pre = sample(phantom, p.grid);
  p.cement = {-8.2, -5.1, 0.3};
  p.leak = {11.0, 10.0, -4.0};
  p.post = sample(phantom, p.grid, {}, {p.cement, p.cementRadius, 3000.0});
  const ImageType::Pointer leak = sample(phantom, p.grid, {}, {p.leak, p.leakRadius, 3000.0});
  // Add the second ball: wherever leak differs from pre.
  for (std::size_t i = 0; i < p.pre->GetLargestPossibleRegion().GetNumberOfPixels(); ++i)
    if (leak->GetBufferPointer()[i] != p.pre->GetBufferPointer()[i])
      p.post->GetBufferPointer()[i] = leak->GetBufferPointer()[i];
  return p;
}

double ballMl(double r) { return 4.0 / 3.0 * M_PI * r * r * r / 1000.0; }

// The synthetic cement has a smooth (logistic) edge: a threshold at half its contrast over tissue
// (~3000 HU over ~0 +- 400 HU) puts the mask's edge at the ball's radius (+-0.1 mm).
SegmentationOptions halfContrast() {
  SegmentationOptions options;
  options.differenceThresholdHU = 1500.0;
  return options;
}

PointType toPoint(const Vec3& v) {
  PointType p;
  for (unsigned i = 0; i < 3; ++i) p[i] = v[i];
  return p;
}

} // namespace

TEST(CementSegmentation, KeepsTheComponentAtTheInjectionPoint) {
  const Pair p = makePair();
  SegmentationOptions options = halfContrast();
  options.injectionPointMm = toPoint(p.cement);
  const SegmentationResult r = segmentCement(p.post, p.pre, options);
  EXPECT_EQ(r.selection, "injection-point");
  EXPECT_EQ(r.componentsFound, 2u);
  EXPECT_NEAR(r.volumeMl, ballMl(p.cementRadius), 0.08 * ballMl(p.cementRadius));
  EXPECT_NEAR(maskVolumeMl(r.mask), r.volumeMl, 1e-12);
  // The leak is not in the mask.
  MaskType::IndexType leakIndex;
  ASSERT_TRUE(r.mask->TransformPhysicalPointToIndex(toPoint(p.leak), leakIndex));
  EXPECT_EQ(r.mask->GetPixel(leakIndex), 0);
}

TEST(CementSegmentation, LargestComponentWithoutInjectionPoint) {
  const Pair p = makePair();
  const SegmentationResult r = segmentCement(p.post, p.pre, halfContrast());
  EXPECT_EQ(r.selection, "largest");
  EXPECT_NEAR(r.volumeMl, ballMl(p.leakRadius), 0.08 * ballMl(p.leakRadius));
}

TEST(CementSegmentation, NearestComponentWhenThePointMissesTheMask) {
  const Pair p = makePair();
  SegmentationOptions options = halfContrast();
  options.injectionPointMm = toPoint({p.cement[0] - 9.0, p.cement[1], p.cement[2]}); // 3 mm outside
  const SegmentationResult r = segmentCement(p.post, p.pre, options);
  EXPECT_EQ(r.selection, "nearest-to-injection-point");
  EXPECT_NEAR(r.distanceToInjectionPointMm, 3.0, 1.1);
  EXPECT_NEAR(r.volumeMl, ballMl(p.cementRadius), 0.08 * ballMl(p.cementRadius));
  // Too far from any cement: nothing is claimed.
  options.injectionPointMm = toPoint({-20, 20, 15});
  options.injectionSearchRadiusMm = 5.0;
  EXPECT_EQ(segmentCement(p.post, p.pre, options).selection, "none");
}

TEST(CementSegmentation, NoCementIsAnHonestZero) {
  const Pair p = makePair();
  SegmentationOptions options;
  options.injectionPointMm = toPoint(p.cement);
  const SegmentationResult r = segmentCement(p.pre, p.pre, options);
  EXPECT_EQ(r.selection, "none");
  EXPECT_EQ(r.voxels, 0u);
  EXPECT_EQ(r.volumeMl, 0.0);
  ASSERT_TRUE(r.mask);
}

TEST(CementSegmentation, ClosingFillsAnInteriorHole) {
  Pair p = makePair();
  // Punch a 1-voxel hole at the cement centre.
  ImageType::IndexType centre;
  ASSERT_TRUE(p.post->TransformPhysicalPointToIndex(toPoint(p.cement), centre));
  p.post->SetPixel(centre, p.pre->GetPixel(centre));
  SegmentationOptions options;
  options.injectionPointMm = toPoint({p.cement[0] + 3, p.cement[1], p.cement[2]});
  const SegmentationResult open = segmentCement(p.post, p.pre, options);
  EXPECT_EQ(open.mask->GetPixel(centre), 0);
  options.closingRadiusMm = 1.0;
  const SegmentationResult closed = segmentCement(p.post, p.pre, options);
  EXPECT_EQ(closed.mask->GetPixel(centre), 1);
  EXPECT_GT(closed.voxels, open.voxels);
}

TEST(CementSegmentation, DifferentGridsAreRejected) {
  const Pair p = makePair();
  Grid other = p.grid;
  other.origin[0] += 1.0;
  const auto shifted = makeImage(other);
  EXPECT_THROW(segmentCement(shifted, p.pre), std::runtime_error);
}

// ---- Half the cement's own contrast (issue 12, item 4) on a ball of known volume with partial-volume
// edges: each voxel holds the fraction of its box inside the ball (6^3 sub-samples), as a CT's voxel
// averages what it covers, times a 2300 HU contrast, over noisy tissue.

namespace {

struct PartialVolumeBall {
  ImageType::Pointer pre, post;
  double volumeMl = 0.0; // the ball's, 4/3 pi r^3
  PointType centre;
};

PartialVolumeBall makePartialVolumeBall(double radiusMm, double contrastHU, double noiseHU) {
  Grid grid;
  grid.size = {48, 48, 48};
  grid.spacing = {0.5, 0.5, 0.5};
  grid.origin = {-11.75, -11.75, -11.75};
  PartialVolumeBall b;
  b.pre = makeImage(grid, 40.0f);
  b.post = makeImage(grid, 40.0f);
  const Vec3 c{0.13, -0.21, 0.07}; // off the voxel lattice
  for (unsigned a = 0; a < 3; ++a) b.centre[a] = c[a];
  b.volumeMl = 4.0 / 3.0 * M_PI * radiusMm * radiusMm * radiusMm / 1000.0;
  std::mt19937 random(20261201);
  std::normal_distribution<double> noise(0.0, noiseHU);
  constexpr int kSub = 6;
  const double halfDiagonal = 0.5 * std::sqrt(3.0) * 0.5;
  for (unsigned k = 0; k < 48; ++k)
    for (unsigned j = 0; j < 48; ++j)
      for (unsigned i = 0; i < 48; ++i) {
        const Vec3 x{grid.origin[0] + 0.5 * i, grid.origin[1] + 0.5 * j, grid.origin[2] + 0.5 * k};
        const double r = std::sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
                                   (x[2] - c[2]) * (x[2] - c[2]));
        double inside = r < radiusMm - halfDiagonal ? 1.0 : 0.0;
        if (std::abs(r - radiusMm) <= halfDiagonal) {
          int hits = 0;
          for (int s = 0; s < kSub * kSub * kSub; ++s) {
            const double dx = ((s % kSub) + 0.5) / kSub - 0.5, dy = ((s / kSub % kSub) + 0.5) / kSub - 0.5,
                         dz = ((s / kSub / kSub) + 0.5) / kSub - 0.5;
            const double px = x[0] + 0.5 * dx - c[0], py = x[1] + 0.5 * dy - c[1], pz = x[2] + 0.5 * dz - c[2];
            hits += px * px + py * py + pz * pz < radiusMm * radiusMm;
          }
          inside = static_cast<double>(hits) / (kSub * kSub * kSub);
        }
        const ImageType::IndexType index{{i, j, k}};
        b.pre->SetPixel(index, static_cast<float>(40.0 + noise(random)));
        b.post->SetPixel(index, static_cast<float>(40.0 + inside * contrastHU + noise(random)));
      }
  return b;
}

} // namespace

TEST(CementSegmentation, HalfContrastGivesTheBallsVolumeWithin2Percent) {
  const PartialVolumeBall b = makePartialVolumeBall(5.0, 2300.0, 25.0);
  SegmentationOptions options; // the default rule
  options.injectionPointMm = b.centre;
  const SegmentationResult r = segmentCement(b.post, b.pre, options);
  EXPECT_EQ(r.thresholdRule, "half-contrast");
  // The plateau is the contrast plus noise (two independent 25 HU draws: sigma 35 HU); its 90th
  // percentile lies 1.3 sigma above, i.e. within 100 HU of 2300, and the threshold within 50 of 1150.
  EXPECT_NEAR(r.cementContrastHU, 2300.0, 100.0);
  EXPECT_NEAR(r.thresholdHU, 1150.0, 50.0);
  std::cout << "ball " << b.volumeMl << " ml: half contrast " << r.volumeMl << " ml at " << r.thresholdHU
            << " HU (contrast " << r.cementContrastHU << " HU)\n";
  EXPECT_NEAR(r.volumeMl, b.volumeMl, 0.02 * b.volumeMl) << "threshold " << r.thresholdHU << " HU";
}

TEST(CementSegmentation, HalfContrastFollowsAWeakerCement) {
  const PartialVolumeBall b = makePartialVolumeBall(4.0, 1200.0, 20.0);
  SegmentationOptions options;
  options.injectionPointMm = b.centre;
  const SegmentationResult r = segmentCement(b.post, b.pre, options);
  EXPECT_NEAR(r.thresholdHU, 600.0, 40.0);
  EXPECT_NEAR(r.volumeMl, b.volumeMl, 0.02 * b.volumeMl);
}

// The old fixed 500 HU (22 % of the contrast) takes in the partial-volume shell: guards that the ball
// above really measures the bias the default removes.
TEST(CementSegmentation, AFixedLowThresholdOverestimatesTheBall) {
  const PartialVolumeBall b = makePartialVolumeBall(5.0, 2300.0, 25.0);
  SegmentationOptions options;
  options.injectionPointMm = b.centre;
  options.differenceThresholdHU = 500.0;
  const SegmentationResult r = segmentCement(b.post, b.pre, options);
  EXPECT_EQ(r.thresholdRule, "fixed");
  EXPECT_EQ(r.thresholdHU, 500.0);
  std::cout << "ball " << b.volumeMl << " ml: fixed 500 HU " << r.volumeMl << " ml\n";
  EXPECT_GT(r.volumeMl, 1.04 * b.volumeMl);
}

TEST(CementSegmentation, NonFiniteThresholdIsRejected) {
  const PartialVolumeBall b = makePartialVolumeBall(3.0, 2300.0, 0.0);
  SegmentationOptions options;
  options.differenceThresholdHU = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(segmentCement(b.post, b.pre, options), std::invalid_argument);
}
