// anatomy_labels.nrrd (issue 20 item 6): `cementsph inject` on the bundled vertebra phantom without --labels
// writes the anatomy the CT bone rule gave the run, on the input CT's grid, with its colour table. Oracles: the
// input's own geometry (size, origin, spacing, direction, exactly as read back), and the phantom's analytic body
// (VertebraPhantom.h: an elliptic cylinder about (32, 21, 22.5) mm, semi-axes 20 x 15 mm, half height 12.5 mm) and
// posterior arch (the ring 8 .. 12 mm about the canal's axis (32, 44) with y >= 35.5 mm, within 10 mm of mid
// height): every voxel whose whole box lies inside the body is the target vertebra (class 1), and the voxels of
// class 1 lie in the body or the arch grown by one voxel (partial volume, the rule's rim).
#include "ProgramRun.h"
#include "RenderingTestSupport.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <itkImageRegionIteratorWithIndex.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

namespace fs = std::filesystem;

namespace {
using cementsph::imaging::ImageType;

const fs::path kPhantom = fs::path(CEMENTSPH_TEST_DATA_DIR) / "vertebra-phantom" / "pre.nrrd";

// Inside the body (elliptic cylinder) grown or shrunk by `margin` mm (a conservative test on the semi-axes).
bool inBody(double x, double y, double z, double margin) {
  const double ex = (x - 32) / (20 + margin), ey = (y - 21) / (15 + margin);
  return ex * ex + ey * ey <= 1 && std::abs(z - 22.5) <= 12.5 + margin;
}
bool inArch(double x, double y, double z, double margin) {
  const double rc = std::hypot(x - 32, y - 44);
  return rc >= 8 - margin && rc <= 12 + margin && y >= 35.5 - margin && std::abs(z - 22.5) <= 10 + margin;
}

TEST(AnatomyLabels, InjectWritesTheBoneRulesAnatomyOnTheInputGrid) {
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "anatomy-labels";
  fs::remove_all(out);
  const auto r = cementsph::testing::runProgram(
      CEMENTSPH_EXECUTABLE,
      {"inject", "--ct", kPhantom.string(), "--scene", (fs::path(CEMENTSPH_TEST_DATA_DIR) / "scenes" / "paper-1ml.json").string(),
       "--tip-mm", "35,30,22.5", "--set", "direction=[-0.3,-0.954,0]", "--volume-ml", "0.5", "--no-pictures",
       "--quiet", "--out", out.string()});
  ASSERT_EQ(r.exitCode, 0) << r.err;
  ASSERT_TRUE(fs::exists(out / "anatomy_labels.nrrd"));
  ASSERT_TRUE(fs::exists(out / "anatomy_labels.ctbl"));
  std::ifstream table(out / "anatomy_labels.ctbl");
  const std::string text((std::istreambuf_iterator<char>(table)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("1 target_vertebra"), std::string::npos) << text;
  EXPECT_NE(text.find("3 canal"), std::string::npos) << text;

  const auto ct = cementsph::imaging::readVolume(kPhantom.string());
  const auto labels = cementsph::imaging::readVolume((out / "anatomy_labels.nrrd").string());
  EXPECT_EQ(labels->GetLargestPossibleRegion(), ct->GetLargestPossibleRegion());
  for (unsigned a = 0; a < 3; ++a) {
    EXPECT_DOUBLE_EQ(labels->GetOrigin()[a], ct->GetOrigin()[a]);
    EXPECT_DOUBLE_EQ(labels->GetSpacing()[a], ct->GetSpacing()[a]);
    for (unsigned b = 0; b < 3; ++b) EXPECT_DOUBLE_EQ(labels->GetDirection()(a, b), ct->GetDirection()(a, b));
  }

  // Half a voxel's diagonal: a voxel whose centre is this far inside the body lies wholly inside it.
  const auto s = ct->GetSpacing();
  const double halfDiagonal = 0.5 * std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
  const double voxel = std::max({s[0], s[1], s[2]});
  std::size_t deepInBody = 0, deepClassed = 0, vertebra = 0, vertebraInShape = 0;
  itk::ImageRegionIteratorWithIndex<ImageType> it(labels, labels->GetLargestPossibleRegion());
  for (; !it.IsAtEnd(); ++it) {
    ImageType::PointType p;
    labels->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    const bool target = std::lround(it.Get()) == 1;
    if (inBody(p[0], p[1], p[2], -halfDiagonal)) {
      ++deepInBody;
      deepClassed += target ? 1 : 0;
    }
    if (target) {
      ++vertebra;
      vertebraInShape += inBody(p[0], p[1], p[2], voxel) || inArch(p[0], p[1], p[2], voxel) ? 1 : 0;
    }
  }
  const double bodyFound = double(deepClassed) / double(deepInBody), inShape = double(vertebraInShape) / double(vertebra);
  std::cout << "anatomy_labels.nrrd: " << deepClassed << " of " << deepInBody << " voxels wholly in the body are the "
            << "target vertebra (" << bodyFound << "); " << vertebraInShape << " of " << vertebra
            << " target voxels lie in the body or arch grown by a voxel (" << inShape << ")\n";
  EXPECT_GE(bodyFound, 0.99);
  EXPECT_GE(inShape, 0.98);
}

// The pictures draw that vertebra without --labels: cement_slices.png outlines it (CementSlices.h's outline
// colour, (0, 200, 80)) on every panel, and cement_surface.png draws it translucent around the cement, so its
// beige (an unlit (204, 184, 140) blended over white: red above blue, neither grey nor the cement's blue) covers a
// large share of the picture. Oracle for the share: the body's projection is at least a 40 x 25 mm rectangle
// (its section), which at any view takes more than 2 % of the 800 x 634 px area at the picture's scale (the
// framing box's diagonal, 0.55 x of which is half the height, is under 120 mm for the 64 x 70 x 45 mm field).
TEST(AnatomyLabels, InjectsPicturesShowTheVertebraWithoutLabels) {
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "anatomy-pictures";
  fs::remove_all(out);
  const auto r = cementsph::testing::runProgram(
      CEMENTSPH_EXECUTABLE,
      {"inject", "--ct", kPhantom.string(), "--scene", (fs::path(CEMENTSPH_TEST_DATA_DIR) / "scenes" / "paper-1ml.json").string(),
       "--tip-mm", "35,30,22.5", "--set", "direction=[-0.3,-0.954,0]", "--volume-ml", "0.5", "--quiet", "--out",
       out.string()});
  ASSERT_EQ(r.exitCode, 0) << r.err;
  std::size_t outline = 0;
  for (const auto& rgb : cementsph::rendering::test::readPicture(out / "cement_slices.png").pixels)
    outline += rgb == cementsph::rendering::test::Picture::Rgb{0, 200, 80} ? 1 : 0;
  EXPECT_GE(outline, 300u) << "no vertebra outline";
  const auto surface = cementsph::rendering::test::readPicture(out / "cement_surface.png");
  std::size_t beige = 0;
  for (const auto& c : surface.pixels)
    beige += c[0] > c[2] + 10 && c[1] > c[2] && c[0] < 250 && std::abs(c[0] - c[1]) < 40 ? 1 : 0;
  EXPECT_GT(double(beige) / double(surface.pixels.size()), 0.02) << beige << " beige pixels";
}

} // namespace
