// cement_surface.png with the vertebra around the cement (CementSurface.h, issue 20 item 6). A synthetic scene
// whose picture can be worked out by hand: a cylinder of "vertebra" voxels (axis z through (30, 30), radius
// 20 mm, z 10 .. 50 mm) on a 61^3 grid of 1 mm voxels, a ball of cement (radius 6 mm) at its centre, seen from
// above (view direction +z, up +y). The oracle is the header's camera: parallel projection, the focal point the
// centre of the surfaces' box, half the 3D area's height 0.55 x the box's diagonal. The box is the cylinder's
// isosurface box, voxel centres +- half a voxel: x, y, z in [9.5, 50.5], so its centre is (30, 30, 30) and its
// diagonal 41 sqrt 3 = 71.01 mm; the 3D area is 800 x 633.6 px (the lower 88 % of 720), so a millimetre is
// 316.8 / (0.55 x 71.01) = 8.11 px and the centre (30, 30) is at pixel (400, 86.4 + 316.8 = 403).
#include "RenderingTestSupport.h"
#include "cementsph/rendering/CementSurface.h"

#include <gtest/gtest.h>
#include <vtkImageData.h>

#include <cmath>
#include <functional>

namespace {
using cementsph::rendering::test::Picture;

vtkSmartPointer<vtkImageData> grid(const std::function<bool(double, double, double)>& inside) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(61, 61, 61);
  image->SetSpacing(1, 1, 1);
  image->SetOrigin(0, 0, 0);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  for (int k = 0; k < 61; ++k)
    for (int j = 0; j < 61; ++j)
      for (int i = 0; i < 61; ++i)
        image->SetScalarComponentFromDouble(i, j, k, 0, inside(i, j, k) ? 1 : 0);
  return image;
}

constexpr double kPxPerMm = 316.8 / (0.55 * 41.0 * 1.7320508075688772);
int column(double xMm) { return int(std::lround(400 + (xMm - 30) * kPxPerMm)); }
constexpr int kRow = 403;

bool white(const Picture::Rgb& c) { return c[0] >= 250 && c[1] >= 250 && c[2] >= 250; }

TEST(CementSurfaceVertebra, TheCementShowsThroughTheTranslucentVertebraWhereTheyProject) {
  const auto cement = grid([](double x, double y, double z) { return std::hypot(x - 30, y - 30, z - 30) <= 6; });
  const auto vertebra =
      grid([](double x, double y, double z) { return std::hypot(x - 30, y - 30) <= 20 && z >= 10 && z <= 50; });
  cementsph::rendering::CementSurfaceOptions o;
  o.viewDirection[0] = 0;
  o.viewDirection[1] = 0;
  o.viewDirection[2] = 1;
  o.viewUp[0] = 0;
  o.viewUp[1] = 1;
  o.viewUp[2] = 0;
  const auto dir = cementsph::rendering::test::scratchFolder();
  const auto bare = dir / "bare.png", withVertebra = dir / "vertebra.png";
  o.vertebraMask = vertebra;
  cementsph::rendering::writeCementSurface(cement, withVertebra, o);
  const Picture p = cementsph::rendering::test::readPicture(withVertebra);
  ASSERT_EQ(p.width, 800);
  ASSERT_EQ(p.height, 720);
  // The cement's centre: its blue through the vertebra's top (a quarter opaque): blue dominates.
  const auto centre = p.at(column(30), kRow);
  EXPECT_GT(centre[2], centre[0] + 40) << centre[0] << " " << centre[1] << " " << centre[2];
  // Inside the vertebra's outline, outside the cement's (14 mm from the axis: cement 6, vertebra 20): the
  // vertebra's ink, beige (red over blue), not the white background.
  for (double x : {30 - 14.0, 30 + 14.0}) {
    const auto c = p.at(column(x), kRow);
    EXPECT_FALSE(white(c)) << "x " << x << ": " << c[0] << " " << c[1] << " " << c[2];
    EXPECT_GT(c[0], c[2]) << "x " << x;
  }
  // Outside the vertebra's outline (25 mm from the axis; the box is 50.5 mm wide, the 3D area 96 mm): background.
  for (double x : {30 - 25.0, 30 + 25.0}) EXPECT_TRUE(white(p.at(column(x), kRow))) << "x " << x;
  // Without the vertebra the same view frames the cement alone: 14 mm from its centre is background.
  o.vertebraMask = nullptr;
  cementsph::rendering::writeCementSurface(cement, bare, o);
  const Picture b = cementsph::rendering::test::readPicture(bare);
  const auto bareCentre = b.at(400, kRow);
  EXPECT_GT(bareCentre[2], bareCentre[0] + 40);
}

TEST(CementSurfaceVertebra, AVertebraLabelMapWithoutScalarsIsOneClearError) {
  const auto cement = grid([](double x, double y, double z) { return std::hypot(x - 30, y - 30, z - 30) <= 6; });
  auto empty = vtkSmartPointer<vtkImageData>::New();
  cementsph::rendering::CementSurfaceOptions o;
  o.vertebraMask = empty;
  const auto dir = cementsph::rendering::test::scratchFolder();
  EXPECT_THROW(cementsph::rendering::writeCementSurface(cement, dir / "x.png", o), std::invalid_argument);
}

} // namespace
