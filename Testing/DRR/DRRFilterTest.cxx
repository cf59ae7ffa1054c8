// vtkDRRFilter against geometry and analytic line integrals:
//  - the exact voxel walk: a homogeneous box integrates to mu * (chord through the box) for any ray;
//  - a homogeneous sphere (HU 1000, mu = 0.044 /mm) in air: pixels equal 2 sqrt(R^2 - b^2) mu / 10
//    (parallel beam and cone beam through the centre), and rays that miss it are exactly 0;
//  - magnification sid/sad of a sphere's projected size; a gantry rotation moves an off-centre ball
//    where the (hand-derived) geometry says; a translated volume or one stored with another direction
//    matrix gives the projection the physical object should give.
#include "DRRTestVolumes.h"
#include "cementsph/drr/AttenuationVolume.h"
#include "cementsph/drr/vtkDRRFilter.h"

#include <gtest/gtest.h>
#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>

#include <cmath>
#include <random>
#include <vector>

using namespace cementsph::drrtest;
using cementsph::drr::AttenuationVolume;
using cementsph::drr::DRRGeometry;
using cementsph::drr::Ray;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMuBone1000 = 0.044; // mu of HU 1000, 1/mm

struct Drr {
  int cols = 0, rows = 0;
  double pixelW = 0, pixelH = 0;
  std::vector<float> v;
  double at(int i, int j) const { return v[static_cast<std::size_t>(j) * cols + i]; }
  double sum() const {
    double s = 0;
    for (float x : v) s += x;
    return s;
  }
  // Intensity-weighted centroid in pixel coordinates, and radius of gyration in pixels.
  std::array<double, 3> moments() const {
    double s = 0, si = 0, sj = 0;
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < cols; ++i) {
        s += at(i, j);
        si += at(i, j) * i;
        sj += at(i, j) * j;
      }
    const double ci = si / s, cj = sj / s;
    double r2 = 0;
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < cols; ++i) r2 += at(i, j) * ((i - ci) * (i - ci) + (j - cj) * (j - cj));
    return {ci, cj, std::sqrt(r2 / s)};
  }
};

Drr project(vtkImageData* volume, const DRRGeometry& g, int threads = 0) {
  vtkNew<vtkDRRFilter> f;
  f->SetInputData(volume);
  f->SetSourceAxisDistance(g.sadMm);
  f->SetSourceImageDistance(g.sidMm);
  f->SetDetectorRows(g.rows);
  f->SetDetectorColumns(g.cols);
  f->SetDetectorHeight(g.heightMm);
  f->SetDetectorWidth(g.widthMm);
  f->SetIsocenter(g.isocenterMm[0], g.isocenterMm[1], g.isocenterMm[2]);
  f->SetGantryAngle(g.gantryAngleDeg);
  f->SetParallelBeam(g.parallel);
  f->SetNumberOfThreads(threads);
  f->Update();
  EXPECT_EQ(f->GetErrorCode(), 0u);
  vtkImageData* out = f->GetOutput();
  Drr d;
  int dims[3];
  out->GetDimensions(dims);
  d.cols = dims[0];
  d.rows = dims[1];
  EXPECT_EQ(dims[2], 1);
  EXPECT_EQ(out->GetScalarType(), VTK_FLOAT);
  d.pixelW = out->GetSpacing()[0];
  d.pixelH = out->GetSpacing()[1];
  const float* p = static_cast<const float*>(out->GetScalarPointer());
  d.v.assign(p, p + static_cast<std::size_t>(d.cols) * d.rows);
  return d;
}

DRRGeometry detector(int n, double sizeMm, bool parallel, const Vec3& iso = {0, 0, 0}) {
  DRRGeometry g;
  g.rows = g.cols = n;
  g.heightMm = g.widthMm = sizeMm;
  g.parallel = parallel;
  g.isocenterMm = iso;
  return g;
}

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

TEST(AttenuationVolume, HUToMuIsPlastimatchs) {
  EXPECT_DOUBLE_EQ(AttenuationVolume::muFromHU(0.0), 0.022);
  EXPECT_DOUBLE_EQ(AttenuationVolume::muFromHU(1000.0), 0.044);
  EXPECT_DOUBLE_EQ(AttenuationVolume::muFromHU(-800.0), 0.0);
  EXPECT_NEAR(AttenuationVolume::muFromHU(-799.0), 0.022 * 0.201, 1e-12);
  EXPECT_DOUBLE_EQ(AttenuationVolume::muFromHU(-1000.0), 0.0);
}

TEST(AttenuationVolume, VoxelWalkIsExactThroughAHomogeneousBox) {
  // A 7x5x6 box of HU 0 (mu 0.022) with anisotropic voxels, an oblique direction matrix and an
  // offset origin: every ray must integrate to mu times its chord through the box, whatever voxels
  // it crosses (the walk has no sampling error).
  VolumeGrid grid;
  grid.dims = {7, 5, 6};
  grid.spacing = {1.3, 0.7, 2.1};
  grid.origin = {4.0, -3.0, 2.5};
  const double c = std::cos(0.4), s = std::sin(0.4);
  grid.direction = {c, 0, s, 0, 1, 0, -s, 0, c};
  grid.subsamples = 1;
  auto box = voxelise(grid, [](const Vec3&) { return 0.0; });
  const AttenuationVolume volume(box, 1);
  ASSERT_EQ(volume.attenuatingVoxels(), 7u * 5u * 6u);

  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0;
  for (int n = 0; n < 2000; ++n) {
    Ray r;
    r.origin = {5.0 + 20 * u(rng), 20 * u(rng), 8.0 + 20 * u(rng)};
    // Aimed near the box (centre about (9.6, -1.6, 5.8)) so that most rays cross it.
    Vec3 d{9.6 + 6 * u(rng) - r.origin[0], -1.6 + 4 * u(rng) - r.origin[1], 5.8 + 6 * u(rng) - r.origin[2]};
    if (n % 10 == 0) d = {0.0, 1.0, 0.0}; // axis-parallel rays too
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (double& x : d) x /= len;
    r.direction = d;
    r.tMin = 0.0;
    r.tMax = 60.0;
    // Chord by slab clipping in the box's own frame (index space; ray parameter in mm).
    double t0 = r.tMin, t1 = r.tMax;
    for (int a = 0; a < 3; ++a) {
      // Box axis a: direction column a; its extent along it is [-0.5, dims - 0.5] * spacing.
      const Vec3 axis{grid.direction[a], grid.direction[3 + a], grid.direction[6 + a]};
      double o = 0, dd = 0;
      for (int k = 0; k < 3; ++k) {
        o += axis[k] * (r.origin[k] - grid.origin[k]);
        dd += axis[k] * d[k];
      }
      const double lo = -0.5 * grid.spacing[a], hi = (grid.dims[a] - 0.5) * grid.spacing[a];
      if (std::abs(dd) < 1e-15) {
        if (o < lo || o > hi) t1 = -1;
        continue;
      }
      double ta = (lo - o) / dd, tb = (hi - o) / dd;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    const double expected = t1 > t0 ? 0.022 * (t1 - t0) : 0.0;
    hits += expected > 0;
    // mu is stored as float: relative agreement to 1e-7.
    ASSERT_NEAR(volume.lineIntegral(r), expected, 1e-7 * expected + 1e-12) << "ray " << n;
  }
  EXPECT_GT(hits, 1000);
}

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

TEST(vtkDRRFilterTest, ThreadsDoNotChangeNumbersAndProgressIsReported) {
  const VolumeGrid grid = centredGrid({48, 40, 32}, {1.0, 1.2, 1.5}, {0, 0, 0});
  auto volume = voxelise(grid, balls({{{0, 0, 0}, 15.0, 500.0}, {{4, 4, 4}, 4.0, 3000.0}}));
  const DRRGeometry g = detector(64, 100.0, false);
  const Drr one = project(volume, g, 1), two = project(volume, g, 2);
  EXPECT_EQ(one.v, two.v);

  vtkNew<vtkDRRFilter> f;
  f->SetInputData(volume);
  f->SetDetectorRows(64);
  f->SetDetectorColumns(48);
  std::vector<double> progress;
  vtkNew<vtkCallbackCommand> cb;
  cb->SetClientData(&progress);
  cb->SetCallback([](vtkObject* caller, unsigned long, void* client, void*) {
    static_cast<std::vector<double>*>(client)->push_back(static_cast<vtkAlgorithm*>(caller)->GetProgress());
  });
  f->AddObserver(vtkCommand::ProgressEvent, cb);
  f->Update();
  ASSERT_GE(progress.size(), 3u);
  EXPECT_DOUBLE_EQ(progress.back(), 1.0);
  for (std::size_t k = 1; k < progress.size(); ++k) EXPECT_GE(progress[k], progress[k - 1]);
  int dims[3];
  f->GetOutput()->GetDimensions(dims);
  EXPECT_EQ(dims[0], 48);
  EXPECT_EQ(dims[1], 64);
  // Output geometry: pixel size in mm, detector centre at (0, 0).
  EXPECT_DOUBLE_EQ(f->GetOutput()->GetSpacing()[0], 400.0 / 48);
  EXPECT_DOUBLE_EQ(f->GetOutput()->GetOrigin()[0], -0.5 * 47 * 400.0 / 48);
}

TEST(vtkDRRFilterTest, RefusesABadGeometry) {
  const VolumeGrid grid = centredGrid({8, 8, 8}, {1.0, 1.0, 1.0}, {0, 0, 0});
  auto volume = voxelise(grid, balls({{{0, 0, 0}, 3.0, 500.0}}));
  vtkNew<vtkDRRFilter> f;
  f->SetInputData(volume);
  f->SetSourceAxisDistance(1000.0);
  f->SetSourceImageDistance(900.0);
  vtkObject::GlobalWarningDisplayOff(); // the refusal is expected; keep the test log clean
  f->Update();
  vtkObject::GlobalWarningDisplayOn();
  EXPECT_EQ(f->GetOutput()->GetNumberOfPoints(), 0); // nothing computed
  DRRGeometry g = f->GetGeometry();
  EXPECT_FALSE(g.validate().empty());
  g.sidMm = 1500.0;
  EXPECT_TRUE(g.validate().empty());
  g.rows = 0;
  EXPECT_FALSE(g.validate().empty());
}

TEST(DRRGeometryTest, ExtentThatDoesNotStartAtZeroIsHonoured) {
  // VTK places voxel (i, j, k) of the extent at origin + spacing * (i, j, k): the same voxels stored
  // with an extent starting at (3, -2, 4) and the origin moved back by as much are the same object.
  const VolumeGrid grid = centredGrid({31, 29, 27}, {1.0, 1.0, 1.0}, {0, 0, 0});
  auto a = voxelise(grid, balls({{{1.1, -2.3, 0.7}, 9.3, 700.0}, {{4.2, 3.1, -2.2}, 3.2, 2500.0}}));
  auto b = vtkSmartPointer<vtkImageData>::New();
  b->DeepCopy(a);
  b->SetExtent(3, 33, -2, 26, 4, 30);
  b->SetOrigin(grid.origin[0] - 3.0, grid.origin[1] + 2.0, grid.origin[2] - 4.0);
  for (bool parallel : {true, false}) {
    const Drr da = project(a, detector(61, 61.0, parallel)), db = project(b, detector(61, 61.0, parallel));
    ASSERT_EQ(da.v.size(), db.v.size());
    for (std::size_t k = 0; k < da.v.size(); ++k) ASSERT_EQ(da.v[k], db.v[k]) << k;
  }
}
