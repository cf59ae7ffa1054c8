// Cement segmentation on synthetic pre/post pairs: the component at the injection point (not the
// largest bright region) is kept, volume in ml, closing, and honest zeros when there is no cement.
#include "SyntheticVolumes.h"
#include "cementsph/imaging/CementSegmentation.h"

#include <gtest/gtest.h>

#include <cmath>

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
