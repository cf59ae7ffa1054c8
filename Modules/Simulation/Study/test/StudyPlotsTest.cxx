// The study's pictures (StudyPlots.h) and the point labels they need from XYPlot: stored baselines for the
// error-against-wall-time plot (paper Fig. 6) and the spreading-against-viscosity plot (Fig. 8), and checks
// that would fail if the labels, the data or the series were wrong; the end-pressure plot's (Fig. 9) numbers. Rendered headless (no DISPLAY).
#include "RenderingTestSupport.h"
#include "StudyRowsForTests.h"

#include "cementsph/rendering/ImageCompare.h"
#include "cementsph/rendering/XYPlot.h"
#include "cementsph/study/StudyPlots.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace cementsph;
using namespace cementsph::study::testing;
using rendering::test::expectMatchesBaseline;
using rendering::test::forgetDisplay;
using rendering::test::scratchFolder;
using rendering::test::summarisePng;

namespace {

const std::filesystem::path kBaselineDir = CEMENTSPH_BASELINE_DIR;
// As XYPlot's own baseline: about 120 of the 585 000 pixels of a 900 x 650 plot (re-rendering gives 0).
constexpr double kTolerance = 2e-4;

void expectPlot(const std::filesystem::path& png) {
  const auto s = summarisePng(png);
  EXPECT_EQ(s.width, 900);
  EXPECT_EQ(s.height, 650);
  EXPECT_GT(s.distinctColours, 20u) << "blank?";
  EXPECT_GT(s.nonWhiteFraction, 0.01);
  EXPECT_LT(s.nonWhiteFraction, 0.6);
}

} // namespace

TEST(StudyPlots, ErrorVsWallTimeSpecHasOneSeriesPerIntegratorLabelledByRadius) {
  auto rows = paperLikeRows();
  rows[3].failure = "unstable"; // overdamped 0.57: left out
  const rendering::PlotSpec spec = study::errorVsWallTimeSpec(rows);
  EXPECT_TRUE(spec.logX);
  EXPECT_FALSE(spec.logY);
  ASSERT_EQ(spec.series.size(), 2u);
  EXPECT_EQ(spec.series[0].name, "central-difference"); // order of first appearance: the reference ran first
  EXPECT_EQ(spec.series[1].name, "overdamped");
  // Coarse to fine, the reference marked; the failed run is missing.
  EXPECT_EQ(spec.series[0].pointLabels,
            (std::vector<std::string>{"1.00", "0.75", "0.57", "0.50", "0.45 (ref.)"}));
  EXPECT_EQ(spec.series[1].pointLabels, (std::vector<std::string>{"1.00", "0.75", "0.50", "0.45"}));
  EXPECT_EQ(spec.series[0].x.back(), 90.0);
  EXPECT_EQ(spec.series[0].y.back(), 0.0);
  EXPECT_EQ(spec.series[1].y.front(), 1.10);
  EXPECT_EQ(*spec.yMin, 0.0);
  EXPECT_NEAR(*spec.yMax, 1.3 * 1.10, 1e-12);
  EXPECT_NEAR(*spec.xMin, 1.5 / 1.5, 1e-12);
  EXPECT_NEAR(*spec.xMax, 90.0 * 2, 1e-12);
  for (auto& r : rows) r.failure = "unstable";
  EXPECT_THROW(study::errorVsWallTimeSpec(rows), std::runtime_error);
}

TEST(StudyPlotsRegression, ErrorVsWallTimeMatchesBaseline) {
  forgetDisplay();
  const auto png = scratchFolder() / "error_vs_wall_time.png";
  study::writeErrorVsWallTimePlot(paperLikeRows(), png);
  expectPlot(png);
  expectMatchesBaseline(png, kBaselineDir, "study_error_vs_wall_time.png", kTolerance);
}

// Guards the comparison: if this passed too, the baseline test would prove nothing.
TEST(StudyPlotsRegression, DifferentErrorsDoNotMatchBaseline) {
  forgetDisplay();
  auto rows = paperLikeRows();
  for (auto& r : rows)
    if (r.spec.integrator == "overdamped") *r.errors.surfaceErrorMm *= 0.6;
  const auto png = scratchFolder() / "changed.png";
  study::writeErrorVsWallTimePlot(rows, png);
  const double difference = rendering::imageDifference(png, kBaselineDir / "study_error_vs_wall_time.png");
  std::cout << "difference of changed errors from the baseline: " << difference << "\n";
  EXPECT_GT(difference, 2 * kTolerance);
}

TEST(StudyPlots, SpreadingVsViscositySpecHoldsTheSweepsSpreading) {
  const std::vector<study::StudyRow> sweep{viscosityRow(50, 6.23), viscosityRow(100, 5.78), viscosityRow(200, 5.35),
                                           viscosityRow(400, 4.95)};
  const rendering::PlotSpec spec = study::spreadingVsViscositySpec(sweep);
  ASSERT_EQ(spec.series.size(), 2u);
  EXPECT_EQ(spec.series[0].y, (std::vector<double>{6.23, 5.78, 5.35, 4.95}));
  EXPECT_NEAR(spec.series[1].y[0], 6.63, 1e-12);
}

// Regression: the drawn plot against Testing/Data/Baselines/study_spreading_vs_viscosity.png (see its README.md).
TEST(StudyPlotsRegression, SpreadingVsViscosityMatchesBaseline) {
  forgetDisplay();
  const std::vector<study::StudyRow> sweep{viscosityRow(50, 6.23), viscosityRow(100, 5.78), viscosityRow(200, 5.35),
                                           viscosityRow(400, 4.95)};
  const auto png = scratchFolder() / "spreading_vs_viscosity.png";
  study::writeSpreadingVsViscosityPlot(sweep, png);
  expectPlot(png);
  expectMatchesBaseline(png, kBaselineDir, "study_spreading_vs_viscosity.png", kTolerance);
}

TEST(XYPlotLabels, LabelsAreDrawnBesideThePoints) {
  forgetDisplay();
  rendering::PlotSpec spec;
  spec.title = "labels";
  spec.xLabel = "x";
  spec.yLabel = "y";
  spec.logX = true;
  rendering::PlotSeries s;
  s.name = "points";
  s.style = rendering::PlotSeries::Style::Points;
  s.x = {1, 10, 100};
  s.y = {3, 2, 1};
  spec.series = {s};
  // Labels, like the plot, are clipped to the plot area: keep the points off its edges.
  spec.xMin = 0.5;
  spec.xMax = 400;
  spec.yMin = 0;
  spec.yMax = 4;
  const auto dir = scratchFolder();
  rendering::writePlotPng(spec, dir / "plain.png");
  spec.series[0].pointLabels = {"first point, labelled", "", "third point, labelled"};
  rendering::writePlotPng(spec, dir / "labelled.png");
  const double difference = rendering::imageDifference(dir / "plain.png", dir / "labelled.png");
  std::cout << "labels change " << difference << " of the pixels\n";
  EXPECT_GT(difference, 2 * kTolerance);
  // Lines get labels too.
  spec.series[0].style = rendering::PlotSeries::Style::LineAndPoints;
  rendering::writePlotPng(spec, dir / "line.png");
  spec.series[0].pointLabels.clear();
  rendering::writePlotPng(spec, dir / "line-plain.png");
  EXPECT_GT(rendering::imageDifference(dir / "line.png", dir / "line-plain.png"), 2 * kTolerance);
}

TEST(XYPlotLabels, LabelsMustBeOnePerPoint) {
  forgetDisplay();
  rendering::PlotSpec spec;
  rendering::PlotSeries s;
  s.name = "short";
  s.x = {1, 2};
  s.y = {1, 2};
  s.pointLabels = {"only one"};
  spec.series = {s};
  const auto dir = scratchFolder();
  try {
    rendering::writePlotPng(spec, dir / "bad.png");
    FAIL() << "accepted one label for two points";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("series 'short': 1 point labels for 2 points"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.png"));
}

// The paper's Fig. 9, its simulated half: each finished run's end pressure over the largest, against its
// viscosity. Oracle: the pressures given, divided by hand.
TEST(StudyPlots, EndPressureIsNormalisedByTheSweepsLargest) {
  std::vector<study::StudyRow> rows(4);
  const double viscosity[4] = {50, 100, 200, 400}, endPa[4] = {1000, 1500, 2000, 8000};
  for (int i = 0; i < 4; ++i) {
    rows[i].spec.sweep = study::StudyRunSpec::Sweep::Viscosity;
    rows[i].spec.viscosityPaS = viscosity[i];
    rows[i].finalTipPressurePa = endPa[i];
  }
  rows[2].failure = "unstable"; // a failed run is left out and does not set the scale
  rows[2].finalTipPressurePa = 1e9;
  const rendering::PlotSpec spec = study::endPressureVsViscositySpec(rows);
  ASSERT_EQ(spec.series.size(), 1u);
  EXPECT_EQ(spec.series[0].x, (std::vector<double>{50, 100, 400}));
  ASSERT_EQ(spec.series[0].y.size(), 3u);
  EXPECT_DOUBLE_EQ(spec.series[0].y[0], 1000.0 / 8000.0);
  EXPECT_DOUBLE_EQ(spec.series[0].y[1], 1500.0 / 8000.0);
  EXPECT_DOUBLE_EQ(spec.series[0].y[2], 1.0);
  EXPECT_NE(spec.series[0].name.find("simulated"), std::string::npos);
  EXPECT_NE(spec.title.find("Simulated"), std::string::npos); // one series: no legend, the title says it
  EXPECT_NE(study::endPressureCaption().find("Fig. 9"), std::string::npos);

  std::vector<study::StudyRow> noPressure(1);
  noPressure[0].spec.sweep = study::StudyRunSpec::Sweep::Viscosity;
  EXPECT_THROW(study::endPressureVsViscositySpec(noPressure), std::runtime_error);
}
