// The X-ray sequence pictures (paper Fig. 12) on a machine without a display: the frames picture (no GL:
// pixels composed directly, labels by FreeType) and the projected-area plot (XYPlot, GL under the private
// Xvfb). Each has the expected size, is not blank, matches a stored baseline, and a changed input does not.
#include "RenderingTestSupport.h"

#include "cementsph/rendering/ImageCompare.h"
#include "cementsph/rendering/ProjectedAreaPlot.h"
#include "cementsph/rendering/XrayFramesPicture.h"

#include <gtest/gtest.h>

#include <vtkImageData.h>
#include <vtkPNGReader.h>
#include <vtkSmartPointer.h>

#include <cmath>
#include <iostream>

using namespace cementsph::rendering;
using cementsph::rendering::test::expectMatchesBaseline;
using cementsph::rendering::test::forgetDisplay;
using cementsph::rendering::test::kBaselineDir;
using cementsph::rendering::test::scratchFolder;
using cementsph::rendering::test::summarisePng;

namespace {


// A DRR-like image, 80 x 60 pixels of 0.5 mm: a textured background (bone-like) and a bright blob (cement)
// of radius `radiusPx` at column `cx`; the mask is the blob.
struct FakeFrame {
  vtkSmartPointer<vtkImageData> drr, mask;
};

FakeFrame fakeFrame(double cx, double radiusPx) {
  FakeFrame f;
  f.drr = vtkSmartPointer<vtkImageData>::New();
  f.drr->SetDimensions(80, 60, 1);
  f.drr->SetSpacing(0.5, 0.5, 1.0);
  f.drr->AllocateScalars(VTK_FLOAT, 1);
  f.mask = vtkSmartPointer<vtkImageData>::New();
  f.mask->SetDimensions(80, 60, 1);
  f.mask->SetSpacing(0.5, 0.5, 1.0);
  f.mask->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto* v = static_cast<float*>(f.drr->GetScalarPointer());
  auto* m = static_cast<unsigned char*>(f.mask->GetScalarPointer());
  for (int j = 0; j < 60; ++j)
    for (int i = 0; i < 80; ++i) {
      const double r2 = (i - cx) * (i - cx) + (j - 32.0) * (j - 32.0);
      const bool inside = r2 < radiusPx * radiusPx;
      const double bone = 0.1 + 0.04 * std::sin(i / 4.0) * std::cos(j / 3.0) + 0.002 * j;
      v[j * 80 + i] = static_cast<float>(bone + (inside ? 0.25 * (1.0 - r2 / (radiusPx * radiusPx)) + 0.02 : 0.0));
      m[j * 80 + i] = inside ? 1 : 0;
    }
  return f;
}

// Simulation: background, small, large blob; reference: background, nothing, a blob moved by `shiftPx`.
struct Scene {
  std::vector<FakeFrame> frames;
  std::vector<XrayFramesRow> rows;
};

Scene scene(double shiftPx) {
  Scene s;
  s.frames = {fakeFrame(40, 0), fakeFrame(40, 8), fakeFrame(40, 14), fakeFrame(40, 0), fakeFrame(40 + shiftPx, 13)};
  XrayFramesRow sim{"simulation", {}, {0, 110, 255}, 0.0};
  for (int k = 0; k < 3; ++k) sim.panels.push_back({s.frames[std::size_t(k)].drr, s.frames[std::size_t(k)].mask});
  XrayFramesRow ref{"reference", {}, {255, 120, 0}, 0.0};
  ref.panels = {{s.frames[3].drr, s.frames[3].mask}, {}, {s.frames[4].drr, s.frames[4].mask}};
  s.rows = {sim, ref};
  return s;
}

const std::vector<std::string> kLabels{"t = 0.0 s", "t = 10.0 s", "t = 20.0 s"};

std::size_t countColour(const std::filesystem::path& png, int r, int g, int b) {
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(png.string().c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  const auto* p = static_cast<const unsigned char*>(image->GetScalarPointer());
  const int c = image->GetNumberOfScalarComponents();
  std::size_t n = 0;
  for (vtkIdType k = 0; k < image->GetNumberOfPoints(); ++k)
    if (p[k * c] == r && p[k * c + 1] == g && p[k * c + 2] == b) ++n;
  return n;
}

ProjectedAreaSeries simulatedAreas() {
  ProjectedAreaSeries s{"simulation", {}, {}, {0, 110, 255}, true};
  for (int k = 0; k <= 20; ++k) {
    s.timeS.push_back(k);
    s.areaMm2.push_back(52.0 * std::sqrt(double(k)));
  }
  return s;
}

} // namespace

// The picture's layout and colours against the numbers that define them (the oracle of the regression test below).
TEST(XrayFramesPicture, PanelSizesOutlineColoursAndTheMissingFrame) {
  forgetDisplay();
  const auto png = scratchFolder() / "frames.png";
  const Scene s = scene(3.0);
  renderXrayFrames(s.rows, kLabels, png);
  const auto summary = summarisePng(png);
  // Panels 200 px wide, 150 high (the 40 x 30 mm detector's aspect), 6 px gaps, a 15 px label line on top;
  // the row labels take some 60-120 px on the left.
  EXPECT_EQ(summary.height, 6 + (15 + 6) + 2 * (150 + 6));
  EXPECT_GT(summary.width, 6 + 3 * 206 + 40);
  EXPECT_LT(summary.width, 6 + 3 * 206 + 200);
  EXPECT_GT(summary.distinctColours, 50u);
  EXPECT_GT(summary.nonWhiteFraction, 0.5);
  // The outlines in the rows' colours, the missing reference frame as one light blue-grey panel.
  EXPECT_GT(countColour(png, 0, 110, 255), 100u);
  EXPECT_GT(countColour(png, 255, 120, 0), 50u);
  EXPECT_EQ(countColour(png, 235, 235, 242), 200u * 150u);
}

// Regression: the same picture against Testing/Data/Baselines/xray_frames.png (regenerate: see that folder's
// README.md). No GL: on the same fonts the bytes are identical; 1e-3 of the pixels leaves room for glyph
// rasterisation differences of another FreeType.
TEST(XrayFramesPictureRegression, MatchesBaseline) {
  forgetDisplay();
  const auto png = scratchFolder() / "frames.png";
  const Scene s = scene(3.0);
  renderXrayFrames(s.rows, kLabels, png);
  expectMatchesBaseline(png, "xray_frames.png", 1e-3);
}

TEST(XrayFramesPictureRegression, ShiftedReferenceDoesNotMatchBaseline) {
  const auto png = scratchFolder() / "frames.png";
  renderXrayFrames(scene(-3.0).rows, kLabels, png);
  const double difference = imageDifference(png, kBaselineDir / "xray_frames.png");
  std::cout << "difference of a reference blob moved by 6 px: " << difference << "\n";
  EXPECT_GT(difference, 5e-3);
}

TEST(XrayFramesPicture, BadInputThrowsAndLeavesNoFile) {
  const auto dir = scratchFolder();
  Scene s = scene(3.0);
  EXPECT_THROW(renderXrayFrames({}, kLabels, dir / "a.png"), std::invalid_argument);
  EXPECT_THROW(renderXrayFrames(s.rows, {"only one"}, dir / "b.png"), std::invalid_argument);
  std::vector<XrayFramesRow> uneven = s.rows;
  uneven[1].panels.pop_back();
  EXPECT_THROW(renderXrayFrames(uneven, kLabels, dir / "c.png"), std::invalid_argument);
  std::vector<XrayFramesRow> badMask = s.rows;
  auto small = vtkSmartPointer<vtkImageData>::New();
  small->SetDimensions(10, 10, 1);
  small->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  badMask[0].panels[1].mask = small;
  EXPECT_THROW(renderXrayFrames(badMask, kLabels, dir / "d.png"), std::invalid_argument);
  std::vector<XrayFramesRow> empty{{"nothing", {{}, {}}, {0, 0, 0}, 0.0}};
  EXPECT_THROW(renderXrayFrames(empty, {}, dir / "e.png"), std::invalid_argument);
  EXPECT_THROW(renderXrayFrames(s.rows, kLabels, dir / "missing" / "f.png"), std::runtime_error);
  EXPECT_TRUE(std::filesystem::directory_iterator(dir) == std::filesystem::directory_iterator());
}

TEST(ProjectedAreaPlotRegression, MatchesBaseline) {
  forgetDisplay();
  const auto png = scratchFolder() / "area.png";
  writeProjectedAreaPlot({simulatedAreas(), {"reference", {0.0, 20.0}, {0.0, 190.0}, {255, 120, 0}, false}}, png);
  const auto summary = summarisePng(png);
  EXPECT_EQ(summary.width, 900);
  EXPECT_EQ(summary.height, 650);
  EXPECT_GT(summary.distinctColours, 20u);
  expectMatchesBaseline(png, "projected_area.png", 2e-4); // as the other XYPlot baselines
}

TEST(ProjectedAreaPlotRegression, DifferentCurveDoesNotMatchBaseline) {
  forgetDisplay();
  const auto png = scratchFolder() / "area.png";
  ProjectedAreaSeries slower = simulatedAreas();
  for (double& a : slower.areaMm2) a *= 0.8;
  writeProjectedAreaPlot({slower, {"reference", {0.0, 20.0}, {0.0, 190.0}, {255, 120, 0}, false}}, png);
  const double difference = imageDifference(png, kBaselineDir / "projected_area.png");
  std::cout << "difference of a simulation curve scaled by 0.8: " << difference << "\n";
  EXPECT_GT(difference, 1e-3);
}

TEST(ProjectedAreaPlot, EmptyOrNonFiniteSeriesThrow) {
  forgetDisplay();
  const auto dir = scratchFolder();
  EXPECT_THROW(writeProjectedAreaPlot({}, dir / "a.png"), std::invalid_argument);
  EXPECT_THROW(writeProjectedAreaPlot({{"s", {0, 1}, {0}, {0, 0, 0}, true}}, dir / "b.png"), std::invalid_argument);
  EXPECT_THROW(writeProjectedAreaPlot({{"s", {0, 1}, {0, std::nan("")}, {0, 0, 0}, true}}, dir / "c.png"),
               std::invalid_argument);
  EXPECT_TRUE(std::filesystem::directory_iterator(dir) == std::filesystem::directory_iterator());
}
