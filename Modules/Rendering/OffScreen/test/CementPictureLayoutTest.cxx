// The layout arithmetic of the cement pictures (CementPictureLayout.h), each against a value worked out by hand
// in the test: a z range of two point sets, a 3-4-5 view direction, the leak legend's wording, the label of a
// voxel found from its physical position. No rendering: these choose what the pictures show.
#include "cementsph/rendering/CementPictureLayout.h"

#include <gtest/gtest.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <initializer_list>

namespace {
using namespace cementsph::rendering;

vtkSmartPointer<vtkPolyData> pointsAtZ(std::initializer_list<double> zs) {
  auto points = vtkSmartPointer<vtkPoints>::New();
  for (double z : zs) points->InsertNextPoint(1.0, 2.0, z);
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  return poly;
}

TEST(CementPictureLayout, ZRangeSpansBothSurfacesAndSkipsNull) {
  const auto a = pointsAtZ({-2.0, 3.0}), b = pointsAtZ({1.0, 7.5});
  const auto range = surfacesZRangeMm({a.Get(), nullptr, b.Get()}, 100.0);
  EXPECT_DOUBLE_EQ(range.first, -2.0);
  EXPECT_DOUBLE_EQ(range.second, 7.5);
}

TEST(CementPictureLayout, ZRangeWithoutCementIsOneSliceAtTheFallback) {
  const auto empty = vtkSmartPointer<vtkPolyData>::New(); // no points: VTK's inverted bounds
  for (const auto& range : {surfacesZRangeMm({nullptr, nullptr}, 21.75), surfacesZRangeMm({empty.Get()}, 21.75)}) {
    EXPECT_DOUBLE_EQ(range.first, 21.75);
    EXPECT_DOUBLE_EQ(range.second, 21.75);
  }
}

TEST(CementPictureLayout, ViewTowardsIsTheUnitVectorRaised) {
  // From (1, 1, 1) to (4, 5, 1): the 3-4-5 triangle, unit vector (0.6, 0.8, 0), raised by 0.35 along z.
  const auto view = viewTowards({1.0, 1.0, 1.0}, {4.0, 5.0, 1.0});
  ASSERT_TRUE(view.has_value());
  EXPECT_NEAR((*view)[0], 0.6, 1e-15);
  EXPECT_NEAR((*view)[1], 0.8, 1e-15);
  EXPECT_NEAR((*view)[2], 0.35, 1e-15);
  // Straight down from 2 mm above with no raise: (0, 0, -1).
  const auto down = viewTowards({0.0, 0.0, 2.0}, {0.0, 0.0, 0.0}, 0.0);
  ASSERT_TRUE(down.has_value());
  EXPECT_DOUBLE_EQ((*down)[2], -1.0);
}

TEST(CementPictureLayout, ViewTowardsTheSamePointKeepsTheDefault) {
  EXPECT_FALSE(viewTowards({3.0, 4.0, 5.0}, {3.0, 4.0, 5.0}).has_value());
  EXPECT_FALSE(viewTowards({3.0, 4.0, 5.0}, {3.0, 4.0, 5.0 + 5e-7}).has_value()); // under 1e-6 mm
}

TEST(CementPictureLayout, LeakNoteWording) {
  EXPECT_EQ(leakNote(0.0254752, 1), "leaked 0.0255 ml at 1 site"); // 3 significant digits
  EXPECT_EQ(leakNote(0.5, 3), "leaked 0.5 ml at 3 sites");
  EXPECT_EQ(leakNote(0.0, 0), "");
}

TEST(CementPictureLayout, LabelAtFindsTheNearestVoxelAndZeroOutside) {
  // 4 x 4 x 4 voxels of 2 mm from (10, 20, 30): voxel (1, 2, 3) is centred at (12, 24, 36) mm.
  auto labels = vtkSmartPointer<vtkImageData>::New();
  labels->SetDimensions(4, 4, 4);
  labels->SetSpacing(2.0, 2.0, 2.0);
  labels->SetOrigin(10.0, 20.0, 30.0);
  labels->AllocateScalars(VTK_SHORT, 1);
  labels->GetPointData()->GetScalars()->Fill(0);
  labels->SetScalarComponentFromDouble(1, 2, 3, 0, 7);
  EXPECT_EQ(labelAt(labels, {12.9, 24.2, 36.0}), 7); // index (1.45, 2.1, 3): nearest (1, 2, 3)
  EXPECT_EQ(labelAt(labels, {13.1, 24.0, 36.0}), 0); // index 1.55 rounds to 2: the next voxel
  EXPECT_EQ(labelAt(labels, {8.8, 20.0, 30.0}), 0);  // index -0.6 rounds to -1: outside
  EXPECT_EQ(labelAt(labels, {100.0, 24.0, 36.0}), 0);
}

} // namespace
