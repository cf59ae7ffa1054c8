// The ITK <-> VTK bridge keeps voxels and geometry: the same index maps to the same physical point.
#include "SyntheticVolumes.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <vtkMatrix3x3.h>

#include <cmath>

using namespace cementsph::imaging;
using cementsph::testing::Grid;

TEST(ItkVtkBridge, RoundTripKeepsGeometryAndPhysicalPoints) {
  Grid g;
  g.size = {7, 9, 11};
  g.spacing = {0.47, 0.6, 0.5};
  g.origin = {3.0, -4.0, 12.5};
  // A rotation about an oblique axis: every entry of the direction matrix is non-trivial.
  const double a = 0.3, b = -0.2;
  g.direction = {std::cos(b), 0, std::sin(b), std::sin(a) * std::sin(b), std::cos(a),
                 -std::sin(a) * std::cos(b), -std::cos(a) * std::sin(b), std::sin(a),
                 std::cos(a) * std::cos(b)};
  auto image = cementsph::testing::makeImage(g);
  for (std::size_t i = 0; i < image->GetLargestPossibleRegion().GetNumberOfPixels(); ++i)
    image->GetBufferPointer()[i] = static_cast<float>(i) * 0.5f;

  vtkSmartPointer<vtkImageData> vtk = toVtk(image);
  int dims[3];
  vtk->GetDimensions(dims);
  EXPECT_EQ(dims[0], 7);
  EXPECT_EQ(dims[1], 9);
  EXPECT_EQ(dims[2], 11);
  for (int i = 0; i < 9; ++i)
    EXPECT_DOUBLE_EQ(vtk->GetDirectionMatrix()->GetData()[i], g.direction[static_cast<std::size_t>(i)]);
  // Physical point of a voxel, both sides.
  for (const auto& ijk : {std::array<int, 3>{0, 0, 0}, {6, 8, 10}, {3, 1, 7}}) {
    double pv[3];
    vtk->TransformIndexToPhysicalPoint(ijk[0], ijk[1], ijk[2], pv);
    PointType pi;
    image->TransformIndexToPhysicalPoint({{ijk[0], ijk[1], ijk[2]}}, pi);
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(pv[r], pi[r], 1e-9);
    EXPECT_FLOAT_EQ(static_cast<float>(vtk->GetScalarComponentAsDouble(ijk[0], ijk[1], ijk[2], 0)),
                    image->GetPixel({{ijk[0], ijk[1], ijk[2]}}));
  }
  auto back = imageFromVtk(vtk);
  EXPECT_TRUE(geometryOf(back).sameGrid(geometryOf(image), 1e-12));
  for (std::size_t i = 0; i < image->GetLargestPossibleRegion().GetNumberOfPixels(); ++i)
    ASSERT_EQ(back->GetBufferPointer()[i], image->GetBufferPointer()[i]);
}

TEST(ItkVtkBridge, MasksBecomeUnsignedChar) {
  auto mask = MaskType::New();
  MaskType::RegionType region;
  region.SetSize({{4, 4, 4}});
  mask->SetRegions(region);
  mask->Allocate();
  mask->FillBuffer(0);
  mask->SetPixel({{1, 2, 3}}, 1);
  auto vtk = toVtk(mask);
  EXPECT_EQ(vtk->GetScalarType(), VTK_UNSIGNED_CHAR);
  EXPECT_EQ(vtk->GetScalarComponentAsDouble(1, 2, 3, 0), 1.0);
  auto back = maskFromVtk(vtk);
  EXPECT_EQ(back->GetPixel({{1, 2, 3}}), 1);
  EXPECT_EQ(back->GetPixel({{0, 0, 0}}), 0);
}

TEST(ItkVtkBridge, VtkExtentNotStartingAtZeroKeepsPhysicalPosition) {
  auto vtk = vtkSmartPointer<vtkImageData>::New();
  vtk->SetExtent(2, 5, 0, 3, 1, 4);
  vtk->SetSpacing(2, 2, 2);
  vtk->SetOrigin(1, 1, 1);
  vtk->AllocateScalars(VTK_FLOAT, 1);
  auto image = imageFromVtk(vtk);
  PointType p;
  image->TransformIndexToPhysicalPoint({{0, 0, 0}}, p);
  EXPECT_DOUBLE_EQ(p[0], 5.0);
  EXPECT_DOUBLE_EQ(p[1], 1.0);
  EXPECT_DOUBLE_EQ(p[2], 3.0);
}
