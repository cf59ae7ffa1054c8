// vtkDRRFilter against geometry and analytic line integrals:
//  - a homogeneous sphere (HU 1000, mu = 0.044 /mm) in air: pixels equal 2 sqrt(R^2 - b^2) mu / 10
//    (parallel beam and cone beam through the centre), and rays that miss it are exactly 0;
//  - magnification sid/sad of a sphere's projected size; a gantry rotation moves an off-centre ball
//    where the (hand-derived) geometry says; a translated volume or one stored with another direction
//    matrix gives the projection the physical object should give.
#include "DRRTestSupport.h"
#include "cementsph/drr/vtkDRRFilter.h"

#include <gtest/gtest.h>
#include <vtkNew.h>

#include <cmath>
#include <vector>

using namespace cementsph::drrtest;
using cementsph::drr::DRRGeometry;
using cementsph::drr::Ray;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMuBone1000 = 0.044; // mu of HU 1000, 1/mm

// The shared sphere: R = 30 mm, HU 1000, centred at the origin, 0.5 mm voxels.
class SphereDRR : public ::testing::Test {
protected:
  static constexpr double kR = 30.0;
  static void SetUpTestSuite() {
    // Odd counts put voxel centres (not faces) on the integer-mm rays the tests read: a ray that runs
    // exactly along a voxel face may take either neighbour, in plastimatch as here.
    const VolumeGrid grid = centredGrid({135, 135, 135}, {0.5, 0.5, 0.5}, {0, 0, 0});
    sphere_ = voxelise(grid, balls({{{0, 0, 0}, kR, 1000.0}}));
  }
  static void TearDownTestSuite() { sphere_ = nullptr; }
  static double chord(double b) { return b < kR ? 2.0 * std::sqrt(kR * kR - b * b) * kMuBone1000 / 10.0 : 0.0; }
  static vtkSmartPointer<vtkImageData> sphere_;
};
vtkSmartPointer<vtkImageData> SphereDRR::sphere_;

} // namespace

TEST_F(SphereDRR, ParallelBeamMatchesChordIntegrals) {
  // 1 mm pixels, 121 of them: pixel 60 is the centre, pixel 60 + k is k mm off it.
  const Drr d = project(sphere_, detector(121, 121.0, true));
  EXPECT_NEAR(d.at(60, 60), chord(0.0), 0.01 * chord(0.0));
  for (double b : {10.0, 15.0, 20.0, 25.0}) {
    const int k = static_cast<int>(b);
    EXPECT_NEAR(d.at(60 + k, 60), chord(b), 0.01 * chord(0.0)) << "b = " << b;
    EXPECT_NEAR(d.at(60, 60 - k), chord(b), 0.01 * chord(0.0)) << "b = " << b;
    const double diag = std::round(b / std::sqrt(2.0));
    EXPECT_NEAR(d.at(60 + static_cast<int>(diag), 60 + static_cast<int>(diag)), chord(diag * std::sqrt(2.0)),
                0.01 * chord(0.0));
  }
  // Total: sum of pixels * pixel area = mu * volume / 10 (the voxelised sphere, within 1 %).
  EXPECT_NEAR(d.sum() * d.pixelW * d.pixelH, kMuBone1000 * 4.0 / 3.0 * kPi * kR * kR * kR / 10.0,
              0.01 * kMuBone1000 * 4.0 / 3.0 * kPi * kR * kR * kR / 10.0);
  // Rays that miss the sphere (b > R + a voxel diagonal) are exactly 0.
  int misses = 0;
  for (int j = 0; j < d.rows; ++j)
    for (int i = 0; i < d.cols; ++i)
      if (std::hypot(i - 60.0, j - 60.0) > kR + 0.9) {
        ++misses;
        ASSERT_EQ(d.at(i, j), 0.0f) << i << "," << j;
      }
  EXPECT_GT(misses, 121 * 121 / 2);
}

TEST_F(SphereDRR, ConeBeamThroughTheCentreMatchesChord) {
  DRRGeometry g = detector(101, 101.0, false);
  for (double angle : {0.0, 37.0, 90.0}) {
    g.gantryAngleDeg = angle;
    const Drr d = project(sphere_, g);
    EXPECT_NEAR(d.at(50, 50), chord(0.0), 0.01 * chord(0.0)) << "gantry " << angle;
    // Off-centre pixel: its ray passes the sphere's centre at b = |(c - s) x dir|.
    const Ray r = g.ray(50 + 12, 50);
    const Vec3 cs{-r.origin[0], -r.origin[1], -r.origin[2]};
    const Vec3& u = r.direction;
    const double b = std::sqrt(std::pow(cs[1] * u[2] - cs[2] * u[1], 2) + std::pow(cs[2] * u[0] - cs[0] * u[2], 2) +
                               std::pow(cs[0] * u[1] - cs[1] * u[0], 2));
    EXPECT_NEAR(b, 12.0 * 1000.0 / 1500.0, 0.05); // the pixel is 12 mm off on the detector, 8 mm at the axis
    EXPECT_NEAR(d.at(62, 50), chord(b), 0.01 * chord(0.0)) << "gantry " << angle;
    // Silhouette: radius sid * R / sqrt(sad^2 - R^2) = 45.04 mm; pixels beyond it (plus a voxel) are 0.
    for (int i = 0; i < d.cols; ++i) {
      if (std::abs(i - 50.0) > 1500.0 * kR / std::sqrt(1000.0 * 1000.0 - kR * kR) + 1.0) {
        ASSERT_EQ(d.at(i, 50), 0.0f) << "pixel " << i;
      }
    }
  }
}

TEST_F(SphereDRR, ProjectedSizeFollowsMagnification) {
  // The radius of gyration of a uniform ball's projection is sqrt(2/5) R * magnification (within
  // 1 %: voxels less than 10 % inside the ball fall below -800 HU and drop out, which shrinks it by
  // ~0.5 %).
  for (auto [sad, sid] : {std::pair{1000.0, 1500.0}, {1000.0, 2000.0}, {800.0, 1000.0}}) {
    DRRGeometry g = detector(201, 150.0, false);
    g.sadMm = sad;
    g.sidMm = sid;
    const Drr d = project(sphere_, g);
    const double rg = d.moments()[2] * d.pixelW;
    EXPECT_NEAR(rg, std::sqrt(0.4) * kR * sid / sad, 0.01 * std::sqrt(0.4) * kR * sid / sad)
        << "sad " << sad << " sid " << sid;
    // The shadow's width along the central row: 2 * sid R / sqrt(sad^2 - R^2), to two pixels, plus
    // up to one magnified voxel on each side (partial voxels reach out to R + 0.43 mm).
    int nonzero = 0;
    for (int i = 0; i < d.cols; ++i) nonzero += d.at(i, 100) > 0.0f;
    const double shadow = 2.0 * sid * kR / std::sqrt(sad * sad - kR * kR);
    EXPECT_GE(nonzero * d.pixelW, shadow - 2.0 * d.pixelW);
    EXPECT_LE(nonzero * d.pixelW, shadow + 2.0 * d.pixelW + 2.0 * 0.5 * sid / sad);
  }
  // Parallel beam: no magnification (0.75 mm pixels: a pitch close to the 0.5 mm voxels would alias).
  const Drr p = project(sphere_, detector(201, 150.0, true));
  EXPECT_NEAR(p.moments()[2] * p.pixelW, std::sqrt(0.4) * kR, 0.01 * std::sqrt(0.4) * kR);
}

TEST(DRRGeometryTest, GantryRotationMovesAnOffCentreBallWhereGeometrySays) {
  // A 3 mm ball at (20, 0, 10) mm and a 2 mm one at (0, -15, 0) (asymmetric), 0.5 mm voxels.
  // Derived by hand from plastimatch's frame: source at iso + sad (cos a, -sin a, 0), detector
  // u axis = (sin a, cos a, 0), up = +z, magnification sid / (sad - (p - iso) . (cos a, -sin a, 0)).
  const VolumeGrid grid = centredGrid({60, 40, 40}, {0.5, 0.5, 0.5}, {12.0, 0.0, 5.0});
  auto volume = voxelise(grid, balls({{{20, 0, 10}, 3.0, 1000.0}}));
  for (double angle : {0.0, 90.0, 180.0, -60.0}) {
    DRRGeometry g = detector(161, 80.0, false);
    g.gantryAngleDeg = angle;
    const Drr d = project(volume, g);
    const double a = angle * kPi / 180.0;
    const Vec3 p{20, 0, 10};
    const double towardSource = p[0] * std::cos(a) - p[1] * std::sin(a);
    const double m = 1500.0 / (1000.0 - towardSource);
    const double uMm = (p[0] * std::sin(a) + p[1] * std::cos(a)) * m, vMm = p[2] * m;
    const auto c = d.moments();
    EXPECT_NEAR((c[0] - 80.0) * d.pixelW, uMm, 0.05) << "gantry " << angle;
    EXPECT_NEAR((c[1] - 80.0) * d.pixelH, vMm, 0.05) << "gantry " << angle;
    // ... and DRRGeometry::project agrees with the hand derivation.
    const auto q = g.project(p);
    EXPECT_NEAR((q[0] - 80.0) * d.pixelW, uMm, 1e-9);
    EXPECT_NEAR((q[1] - 80.0) * d.pixelH, vMm, 1e-9);
  }
}

TEST(DRRGeometryTest, TranslatedVolumeMovesTheProjection) {
  // Parallel beam, gantry 0: u = +y, up = +z, 1 mm pixels. Moving the volume (origin) by
  // (4, 5, -3) mm moves its image by 5 pixels right and 3 down, exactly (same voxels, same rays).
  const VolumeGrid grid = centredGrid({40, 44, 36}, {1.0, 1.0, 1.0}, {0, 0, 0});
  const Phantom object = balls({{{0, 0, 0}, 12.0, 800.0}, {{3, 6, -4}, 4.0, 2000.0}});
  auto original = voxelise(grid, object);
  VolumeGrid moved = grid;
  const Vec3 shift{4.0, 5.0, -3.0};
  for (int a = 0; a < 3; ++a) moved.origin[a] += shift[a];
  auto translated = voxelise(moved, [&](const Vec3& p) { return object({p[0] - shift[0], p[1] - shift[1], p[2] - shift[2]}); });
  const Drr d0 = project(original, detector(81, 81.0, true));
  const Drr d1 = project(translated, detector(81, 81.0, true));
  double maxAbs = 0;
  for (float v : d0.v) maxAbs = std::max(maxAbs, static_cast<double>(v));
  ASSERT_GT(maxAbs, 0.05);
  for (int j = 3; j < 78; ++j)
    for (int i = 0; i < 76; ++i) ASSERT_NEAR(d1.at(i + 5, j - 3), d0.at(i, j), 1e-5 * maxAbs) << i << "," << j;

  // Cone beam with the same translation: the centroid moves to the projection of the moved centre.
  const DRRGeometry cone = detector(161, 120.0, false);
  const auto c0 = project(original, cone).moments();
  const auto c1 = project(translated, cone).moments();
  const double m = 1500.0 / (1000.0 - shift[0]); // nearer the source: larger
  // Centroid of the small-ball phantom ~ its own centroid; check the displacement, which is the
  // moved magnification applied to the moved position minus the original one.
  const auto centroidMm = [&](const std::array<double, 3>& c) { return std::array<double, 2>{(c[0] - 80) * 0.75, (c[1] - 80) * 0.75}; };
  const auto a0 = centroidMm(c0), a1 = centroidMm(c1);
  EXPECT_NEAR(a1[0], (a0[0] / 1.5 + shift[1]) * m, 0.1);
  EXPECT_NEAR(a1[1], (a0[1] / 1.5 + shift[2]) * m, 0.1);
}

TEST(DRRGeometryTest, DirectionMatrixIsHonoured) {
  // The same physical object stored with a rotated-and-flipped direction matrix (index axes along
  // -y, +x, -z) and the matching origin gives the same DRR as the axis-aligned storage.
  // Radii and centres off the sample lattice: a sample exactly on a surface could fall either side
  // through rounding in the two storages, which would be a phantom difference, not a DRR one.
  const Phantom object =
      balls({{{0.07, 0.11, -0.13}, 14.21, 600.0}, {{5.03, -7.09, 3.05}, 5.17, 2500.0}, {{-6.1, 2.07, -8.03}, 3.13, 1500.0}});
  // Odd voxel counts and 1 mm pixels keep parallel rays off voxel faces (see SphereDRR).
  const VolumeGrid plain = centredGrid({41, 41, 41}, {1.0, 1.0, 1.0}, {0, 0, 0});
  VolumeGrid rotated = plain;
  rotated.direction = {0, 1, 0, -1, 0, 0, 0, 0, -1};
  // Voxel (0,0,0) at the physical corner (-20, 20, 20) so both store the same voxel centres.
  rotated.origin = {-20.0, 20.0, 20.0};
  auto a = voxelise(plain, object);
  auto b = voxelise(rotated, object);
  for (double angle : {0.0, 30.0}) {
    for (bool parallel : {true, false}) {
      DRRGeometry g = detector(91, 91.0, parallel);
      g.gantryAngleDeg = angle;
      const Drr da = project(a, g), db = project(b, g);
      double maxAbs = 0, maxDiff = 0;
      for (std::size_t k = 0; k < da.v.size(); ++k) {
        maxAbs = std::max(maxAbs, static_cast<double>(da.v[k]));
        maxDiff = std::max(maxDiff, std::abs(static_cast<double>(da.v[k]) - db.v[k]));
      }
      ASSERT_GT(maxAbs, 0.05);
      EXPECT_LT(maxDiff, 1e-4 * maxAbs) << "gantry " << angle << (parallel ? " parallel" : " cone");
    }
  }
}
