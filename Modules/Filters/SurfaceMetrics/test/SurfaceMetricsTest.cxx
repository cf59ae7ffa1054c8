// Surface and volume metrics against exact answers: concentric spheres (mean distance = delta),
// the larger-mean rule on an asymmetric pair, a ball's mean spreading distance (3R/4), Dice and
// Jaccard on known overlaps, and isosurfaces that honour the image direction.
#include "cementsph/surfacemetrics/Isosurface.h"
#include "cementsph/surfacemetrics/SurfaceDistance.h"
#include "cementsph/surfacemetrics/VolumeMetrics.h"

#include <gtest/gtest.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkStaticCellLocator.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <random>

using namespace cementsph::surfacemetrics;

namespace {

// A 0/1 mask on an n^3 grid (spacing h, origin 0, optional direction) set where inside(p) holds for
// the voxel centre p (physical, mm).
vtkSmartPointer<vtkImageData> voxelise(int n, double h, const std::function<bool(const Point3&)>& inside,
                                       const double* direction = nullptr) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(n, n, n);
  image->SetSpacing(h, h, h);
  image->SetOrigin(0, 0, 0);
  if (direction) image->SetDirectionMatrix(direction);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto* p = static_cast<unsigned char*>(image->GetScalarPointer());
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) *p++ = inside(voxelCentre(image, i, j, k)) ? 1 : 0;
  return image;
}

std::function<bool(const Point3&)> ball(const Point3& c, double r) {
  return [c, r](const Point3& p) {
    return (p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) +
               (p[2] - c[2]) * (p[2] - c[2]) <= r * r;
  };
}

} // namespace

TEST(SurfaceDistance, ConcentricSpheresMeanDistanceIsDelta) {
  // Radii in voxels R = 14.3 and R + delta = 17.8 (delta = 3.5 voxels); off-grid centre.
  const double h = 0.5; // mm
  const Point3 c{24.2 * h, 23.7 * h, 24.9 * h};
  const double r = 14.3 * h, delta = 3.5 * h;
  // Default isosurface: mask smoothed with sigma = 1 voxel (the staircase surface of the raw mask
  // is biased low by 0.15-0.2 voxel; see IsosurfaceOptions).
  auto inner = isosurface(voxelise(50, h, ball(c, r)));
  auto outer = isosurface(voxelise(50, h, ball(c, r + delta)));
  const SurfaceComparison cmp = compareSurfaces(inner, outer);
  EXPECT_NEAR(cmp.aToB.meanMm, delta, 0.1 * h);
  EXPECT_NEAR(cmp.bToA.meanMm, delta, 0.1 * h);
  EXPECT_NEAR(cmp.errorMm, delta, 0.1 * h);
  EXPECT_LT(cmp.aToB.stdMm, 0.2 * h);
  std::cout << "concentric spheres: a->b " << cmp.aToB.meanMm / h << " b->a " << cmp.bToA.meanMm / h
            << " voxels (delta 3.5)\n";
  EXPECT_GE(cmp.hausdorffMm, cmp.hausdorff95Mm);
  EXPECT_GE(cmp.hausdorff95Mm, cmp.errorMm - 0.1 * h);
  EXPECT_GT(inner->GetNumberOfPoints(), 1000);
  // Per-vertex distances stay on the surfaces, for colouring.
  auto* array = inner->GetPointData()->GetArray(kDistanceArrayName);
  ASSERT_NE(array, nullptr);
  EXPECT_EQ(array->GetNumberOfTuples(), inner->GetNumberOfPoints());
  ASSERT_NE(outer->GetPointData()->GetArray(kDistanceArrayName), nullptr);
}

TEST(SurfaceDistance, LargerMeanRulePicksTheRightDirection) {
  // b = a plus a lobe: every vertex of a lies on or near b, but the lobe's vertices are far from a.
  const double h = 0.5;
  const Point3 c{16 * h, 20 * h, 20 * h}, lobe{30 * h, 20 * h, 20 * h};
  auto a = isosurface(voxelise(44, h, ball(c, 10 * h)));
  auto lobed = ball(lobe, 7 * h);
  auto inA = ball(c, 10 * h);
  auto b = isosurface(voxelise(44, h, [&](const Point3& p) { return inA(p) || lobed(p); }));
  SurfaceComparison cmp = compareSurfaces(a, b);
  EXPECT_LT(cmp.aToB.meanMm, cmp.bToA.meanMm);
  EXPECT_EQ(cmp.errorDirection, "b_to_a");
  EXPECT_DOUBLE_EQ(cmp.errorMm, cmp.bToA.meanMm);
  // Swapping the arguments swaps the direction, not the error.
  SurfaceComparison swapped = compareSurfaces(b, a);
  EXPECT_EQ(swapped.errorDirection, "a_to_b");
  EXPECT_DOUBLE_EQ(swapped.errorMm, cmp.errorMm);
  EXPECT_DOUBLE_EQ(swapped.hausdorffMm, cmp.hausdorffMm);
}

// The exact point-to-surface search (vertex grid + vertex-triangle links) against VTK's cell
// locator, on query points scattered inside, on and far outside a lobed surface.
TEST(SurfaceDistance, MatchesVtkCellLocatorOnScatteredPoints) {
  const double h = 0.5;
  auto inA = ball({10 * h, 12 * h, 12 * h}, 7 * h);
  auto inB = ball({17 * h, 12 * h, 12 * h}, 4 * h);
  auto surface = isosurface(voxelise(26, h, [&](const Point3& p) { return inA(p) || inB(p); }));
  auto queries = vtkSmartPointer<vtkPolyData>::New();
  auto points = vtkSmartPointer<vtkPoints>::New();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-20.0, 33.0);
  for (int i = 0; i < 3000; ++i) points->InsertNextPoint(u(rng) * h, u(rng) * h, u(rng) * h);
  queries->SetPoints(points);
  const std::vector<double> d = vertexDistances(queries, surface);
  auto locator = vtkSmartPointer<vtkStaticCellLocator>::New();
  locator->SetDataSet(surface);
  locator->BuildLocator();
  for (vtkIdType i = 0; i < points->GetNumberOfPoints(); ++i) {
    double x[3], closest[3], dist2 = 0;
    vtkIdType cellId;
    int subId;
    points->GetPoint(i, x);
    locator->FindClosestPoint(x, closest, cellId, subId, dist2);
    ASSERT_NEAR(d[static_cast<std::size_t>(i)], std::sqrt(dist2), 1e-9) << "query " << i;
  }
}

TEST(SurfaceDistance, SummaryOfKnownValues) {
  std::vector<double> d(101);
  for (int i = 0; i <= 100; ++i) d[static_cast<std::size_t>(i)] = i;
  const DirectedDistance s = summarise(d);
  EXPECT_DOUBLE_EQ(s.meanMm, 50.0);
  EXPECT_DOUBLE_EQ(s.maxMm, 100.0);
  EXPECT_DOUBLE_EQ(s.p95Mm, 95.0);
  EXPECT_NEAR(s.stdMm, std::sqrt(850.0), 1e-9);
}

TEST(SurfaceDistance, EmptySurfaceIsAnError) {
  auto empty = isosurface(voxelise(8, 1.0, [](const Point3&) { return false; }));
  EXPECT_EQ(empty->GetNumberOfPoints(), 0);
  auto full = isosurface(voxelise(12, 1.0, ball({6, 6, 6}, 3)));
  EXPECT_THROW(compareSurfaces(empty, full), std::invalid_argument);
}

TEST(VolumeMetrics, BallMeanSpreadingDistanceIsThreeQuartersR) {
  const double h = 0.47;
  const Point3 c{30.3 * h, 29.8 * h, 30.1 * h};
  const double r = 22.0 * h;
  auto mask = voxelise(62, h, ball(c, r));
  EXPECT_NEAR(meanSpreadingDistanceMm(mask, c), 0.75 * r, 0.01 * 0.75 * r);
  const double exactMl = 4.0 / 3.0 * M_PI * r * r * r / 1000.0;
  EXPECT_NEAR(volumeMl(mask), exactMl, 0.02 * exactMl);
  bool ok = false;
  const Point3 centroid = centroidMm(mask, &ok);
  ASSERT_TRUE(ok);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(centroid[static_cast<std::size_t>(i)], c[static_cast<std::size_t>(i)], 0.05 * h);
}

TEST(VolumeMetrics, DiceAndJaccardOnKnownOverlaps) {
  auto box = [](int x0) {
    return [x0](const Point3& p) {
      return p[0] >= x0 && p[0] < x0 + 10 && p[1] >= 2 && p[1] < 12 && p[2] >= 2 && p[2] < 12;
    };
  };
  auto a = voxelise(24, 1.0, box(2));
  auto shifted = voxelise(24, 1.0, box(7)); // half of a
  Overlap o = overlap(a, shifted);
  EXPECT_EQ(o.voxelsA, 1000u);
  EXPECT_EQ(o.voxelsBoth, 500u);
  EXPECT_DOUBLE_EQ(o.dice, 0.5);
  EXPECT_DOUBLE_EQ(o.jaccard, 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(overlap(a, a).dice, 1.0);
  EXPECT_DOUBLE_EQ(overlap(a, a).jaccard, 1.0);
  auto far = voxelise(24, 1.0, box(13));
  EXPECT_DOUBLE_EQ(overlap(a, far).dice, 0.0);
  EXPECT_DOUBLE_EQ(overlap(a, far).jaccard, 0.0);
  // Nested: b inside a, |b| = 1000 - 500... a box of 10x10x5 inside a 10x10x10 box.
  auto half = voxelise(24, 1.0, [](const Point3& p) {
    return p[0] >= 2 && p[0] < 7 && p[1] >= 2 && p[1] < 12 && p[2] >= 2 && p[2] < 12;
  });
  o = overlap(a, half);
  EXPECT_DOUBLE_EQ(o.dice, 2.0 * 500 / 1500);
  EXPECT_DOUBLE_EQ(o.jaccard, 0.5);
  auto other = voxelise(20, 1.0, box(2));
  EXPECT_THROW(overlap(a, other), std::invalid_argument);
}

TEST(Isosurface, HonoursTheDirectionMatrix) {
  // A ball in index space; with a rotated direction its surface must be centred on the physical
  // centre of the ball's voxels.
  const double c30 = std::cos(M_PI / 6), s30 = std::sin(M_PI / 6);
  const double dir[9] = {c30, -s30, 0, s30, c30, 0, 0, 0, 1};
  auto mask = vtkSmartPointer<vtkImageData>::New();
  mask->SetDimensions(30, 30, 30);
  mask->SetSpacing(0.5, 0.5, 0.5);
  mask->SetOrigin(10, -5, 3);
  mask->SetDirectionMatrix(dir);
  mask->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto* p = static_cast<unsigned char*>(mask->GetScalarPointer());
  for (int k = 0; k < 30; ++k)
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 30; ++i)
        *p++ = ((i - 12) * (i - 12) + (j - 15) * (j - 15) + (k - 14) * (k - 14) <= 64) ? 1 : 0;
  const Point3 expected = voxelCentre(mask, 12, 15, 14);
  bool ok = false;
  const Point3 centroid = centroidMm(mask, &ok);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(centroid[static_cast<std::size_t>(i)], expected[static_cast<std::size_t>(i)], 1e-9);
  auto surface = isosurface(mask);
  ASSERT_GT(surface->GetNumberOfPoints(), 100);
  Point3 mean{0, 0, 0};
  for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i) {
    double x[3];
    surface->GetPoint(i, x);
    for (int r = 0; r < 3; ++r) mean[static_cast<std::size_t>(r)] += x[r];
  }
  for (int r = 0; r < 3; ++r)
    EXPECT_NEAR(mean[static_cast<std::size_t>(r)] / static_cast<double>(surface->GetNumberOfPoints()),
                expected[static_cast<std::size_t>(r)], 0.05);
}
