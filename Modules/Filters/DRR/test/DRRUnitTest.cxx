// Unit checks of the DRR pieces: HU -> mu, the exact voxel walk on a homogeneous box (any ray, any
// grid orientation), an extent that does not start at 0, thread-count independence, progress events
// and the refusal of a bad geometry or an input without voxel values.
#include "DRRTestSupport.h"
#include "cementsph/drr/AttenuationVolume.h"
#include "cementsph/drr/vtkDRRFilter.h"

#include <gtest/gtest.h>
#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkNew.h>
#include <vtkPointData.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace cementsph::drrtest;
using cementsph::drr::AttenuationVolume;
using cementsph::drr::DRRGeometry;
using cementsph::drr::Ray;

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

TEST(vtkDRRFilterTest, AnInputWithoutScalarsGivesAnEmptyOutput) {
  auto empty = vtkSmartPointer<vtkImageData>::New();
  empty->SetDimensions(4, 4, 4); // geometry but no voxel values
  vtkNew<vtkDRRFilter> f;
  f->SetInputData(empty);
  f->SetDetectorRows(8);
  f->SetDetectorColumns(8);
  std::string message;
  vtkNew<vtkCallbackCommand> onError;
  onError->SetClientData(&message);
  onError->SetCallback([](vtkObject*, unsigned long, void* client, void* callData) {
    *static_cast<std::string*>(client) = static_cast<const char*>(callData);
  });
  f->AddObserver(vtkCommand::ErrorEvent, onError);
  f->Update();
  EXPECT_NE(message.find("no scalars"), std::string::npos) << message;
  EXPECT_EQ(f->GetOutput()->GetPointData()->GetScalars(), nullptr);
}
