// writePlotPng on a machine without a display: exact size, real content, points where the axes put them (the
// oracle), a stored baseline (the regression tests), and input checks that fail cleanly.
#include "RenderingTestSupport.h"

#include "cementsph/rendering/ImageCompare.h"
#include "cementsph/rendering/OffScreenWindow.h"
#include "cementsph/rendering/RenderBackend.h"
#include "cementsph/rendering/VirtualDisplay.h"
#include "cementsph/rendering/XYPlot.h"

#include <vtkRenderer.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <vector>

using namespace cementsph::rendering;
using cementsph::rendering::test::expectMatchesBaseline;
using cementsph::rendering::test::forgetDisplay;
using cementsph::rendering::test::kBaselineDir;
using cementsph::rendering::test::readPicture;
using cementsph::rendering::test::scratchFolder;
using cementsph::rendering::test::summarisePng;

namespace {

// Fraction of visibly changed pixels (imageDifference) allowed against a baseline: about 120 of the
// 585 000 pixels of a 900 x 650 plot. Re-rendering on the same software stack gives 0, and one-pixel
// shifts of text or lines from another Mesa/FreeType version do not count at all; moving a few markers
// (DifferentPlotDoesNotMatchBaseline) changes several times more.
constexpr double kBaselineTolerance = 2e-4;

PlotSpec basicSpec() {
  PlotSpec spec;
  spec.title = "y = x^2";
  spec.xLabel = "x";
  spec.yLabel = "y";
  PlotSeries curve;
  curve.name = "x^2";
  curve.style = PlotSeries::Style::Line;
  for (int i = 0; i <= 40; ++i) {
    const double x = 0.25 * i;
    curve.x.push_back(x);
    curve.y.push_back(x * x);
  }
  PlotSeries samples;
  samples.name = "samples";
  samples.style = PlotSeries::Style::Points;
  samples.rgb = {255, 127, 14};
  for (int i = 0; i <= 10; ++i) {
    const double x = i;
    samples.x.push_back(x);
    samples.y.push_back(x * x + 6.0 * std::sin(1.7 * x));
  }
  spec.series = {curve, samples};
  return spec;
}

void expectNotBlank(const std::filesystem::path& png, int width, int height) {
  const auto s = summarisePng(png);
  EXPECT_EQ(s.width, width);
  EXPECT_EQ(s.height, height);
  EXPECT_GT(s.distinctColours, 20u) << "hardly any colours: blank image?";
  EXPECT_GT(s.nonWhiteFraction, 0.01) << "almost all background";
  EXPECT_LT(s.nonWhiteFraction, 0.6) << "almost no background";
}

bool folderIsEmpty(const std::filesystem::path& dir) {
  return std::filesystem::directory_iterator(dir) == std::filesystem::directory_iterator();
}

} // namespace

namespace {

// The centres (mean pixel, x right, y down) of the 8-connected blobs of pixels within `tolerance` of `rgb`.
std::vector<std::array<double, 2>> blobCentres(const cementsph::rendering::test::Picture& p,
                                               const std::array<int, 3>& rgb, int tolerance) {
  auto matches = [&](int x, int y) {
    const auto c = p.at(x, y);
    for (std::size_t k = 0; k < 3; ++k)
      if (std::abs(c[k] - rgb[k]) > tolerance) return false;
    return true;
  };
  std::vector<char> seen(std::size_t(p.width) * std::size_t(p.height), 0);
  std::vector<std::array<double, 2>> centres;
  for (int y0 = 0; y0 < p.height; ++y0)
    for (int x0 = 0; x0 < p.width; ++x0) {
      if (seen[std::size_t(y0) * std::size_t(p.width) + std::size_t(x0)] || !matches(x0, y0)) continue;
      double sx = 0, sy = 0, n = 0;
      std::vector<std::array<int, 2>> stack{{x0, y0}};
      seen[std::size_t(y0) * std::size_t(p.width) + std::size_t(x0)] = 1;
      while (!stack.empty()) {
        const auto [x, y] = stack.back();
        stack.pop_back();
        sx += x;
        sy += y;
        n += 1;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= p.width || ny >= p.height) continue;
            char& s = seen[std::size_t(ny) * std::size_t(p.width) + std::size_t(nx)];
            if (s || !matches(nx, ny)) continue;
            s = 1;
            stack.push_back({nx, ny});
          }
      }
      centres.push_back({sx / n, sy / n});
    }
  return centres;
}

// Least-squares line v = a + b u; returns {a, b, largest |residual|}.
std::array<double, 3> fitLine(const std::vector<double>& u, const std::vector<double>& v) {
  const double n = double(u.size());
  double su = 0, sv = 0, suu = 0, suv = 0;
  for (std::size_t i = 0; i < u.size(); ++i) {
    su += u[i];
    sv += v[i];
    suu += u[i] * u[i];
    suv += u[i] * v[i];
  }
  const double b = (n * suv - su * sv) / (n * suu - su * su), a = (sv - b * su) / n;
  double worst = 0;
  for (std::size_t i = 0; i < u.size(); ++i) worst = std::max(worst, std::abs(a + b * u[i] - v[i]));
  return {a, b, worst};
}

// Eight known points, one series (so no legend: every blob of its colour is a marker); the y values are a
// permutation, so a plot that swapped, sorted or dropped points, or drew y downwards, shows.
PlotSpec eightPoints() {
  PlotSpec spec;
  spec.title = "points";
  spec.xLabel = "x";
  spec.yLabel = "y";
  PlotSeries points;
  points.name = "points";
  points.style = PlotSeries::Style::Points;
  points.rgb = {200, 0, 200};
  points.x = {1, 2, 3, 4, 5, 6, 7, 8};
  points.y = {3, 7, 1, 9, 4, 6, 2, 8};
  spec.series = {points};
  return spec;
}

// The markers' pixel centres fitted against the data, per axis: {offset, pixels per unit, largest residual}.
std::array<std::array<double, 3>, 2> markerFits(const PlotSpec& spec, const std::filesystem::path& png) {
  writePlotPng(spec, png);
  const auto& rgb = spec.series[0].rgb;
  auto centres = blobCentres(readPicture(png), {rgb[0], rgb[1], rgb[2]}, 40);
  EXPECT_EQ(centres.size(), spec.series[0].x.size()) << "one marker per point";
  if (centres.size() != spec.series[0].x.size()) return {};
  std::sort(centres.begin(), centres.end());
  std::vector<double> px, py;
  for (const auto& c : centres) {
    px.push_back(c[0]);
    py.push_back(c[1]);
  }
  const auto xFit = fitLine(spec.series[0].x, px), yFit = fitLine(spec.series[0].y, py);
  std::cout << "x: " << xFit[1] << " px per unit, worst " << xFit[2] << " px; y: " << yFit[1] << " px per unit, worst "
            << yFit[2] << " px\n";
  return {xFit, yFit};
}

} // namespace

// The oracle of the plot regression tests: a chart maps data to pixels by an affine map per axis, so the markers
// of known points must sit on one straight line per axis, x to the right and y upwards, within a pixel and a
// half (the marker's rasterisation).
TEST(XYPlot, PointsLandWhereTheAxesPutThem) {
  forgetDisplay();
  PlotSpec spec = eightPoints();
  spec.xMin = 0;
  spec.xMax = 9;
  spec.yMin = 0;
  spec.yMax = 10;
  const auto [xFit, yFit] = markerFits(spec, scratchFolder() / "points.png");
  EXPECT_GT(xFit[1], 20.0);  // 9 units across most of 900 px
  EXPECT_LT(yFit[1], -20.0); // up the picture is down its rows
  EXPECT_LT(xFit[2], 1.5);
  EXPECT_LT(yFit[2], 1.5);
}

// Axis limits set the scale: the same points with x over [-9, 9] instead of [0, 9] take half the pixels per
// unit, and with yMax 20 alone (yMin from the data: 1) 10/19 of those over [0, 10]. Within 1 %: the plot
// area is the same, only the ranges change.
TEST(XYPlot, AxisLimitsSetTheScaleAndAOneSidedLimitTakesTheOtherFromTheData) {
  forgetDisplay();
  const auto dir = scratchFolder();
  PlotSpec spec = eightPoints();
  spec.xMin = 0;
  spec.xMax = 9;
  spec.yMin = 0;
  spec.yMax = 10;
  const auto [xFit, yFit] = markerFits(spec, dir / "narrow.png");
  spec.xMin = -9;
  spec.yMin.reset();
  spec.yMax = 20;
  const auto [xWide, yWide] = markerFits(spec, dir / "wide.png");
  EXPECT_NEAR(xWide[1] / xFit[1], 9.0 / 18.0, 0.01 * 9.0 / 18.0);
  EXPECT_NEAR(yWide[1] / yFit[1], 10.0 / 19.0, 0.01 * 10.0 / 19.0);
}

// Regression: the plot against Testing/Data/Baselines/xyplot_basic.png (regenerate: that folder's README.md).
TEST(XYPlotRegression, BasicPlotMatchesBaseline) {
  forgetDisplay();
  const auto png = scratchFolder() / "xyplot_basic.png";
  writePlotPng(basicSpec(), png);
  expectNotBlank(png, 900, 650);
  expectMatchesBaseline(png, "xyplot_basic.png", kBaselineTolerance);
}

// Guards the comparison itself: if this passed, the baseline test would prove nothing.
TEST(XYPlotRegression, DifferentPlotDoesNotMatchBaseline) {
  forgetDisplay();
  PlotSpec spec = basicSpec();
  for (double& y : spec.series[1].y) y *= 0.5;
  const auto png = scratchFolder() / "changed.png";
  writePlotPng(spec, png);
  const double difference = imageDifference(png, kBaselineDir / "xyplot_basic.png");
  std::cout << "difference of a changed plot from the baseline: " << difference << "\n";
  EXPECT_GT(difference, 2.0 * kBaselineTolerance);
}

TEST(XYPlot, LogYPlotRendersAtRequestedSize) {
  forgetDisplay();
  PlotSpec spec;
  spec.title = "exponential on a log axis";
  spec.xLabel = "t (s)";
  spec.yLabel = "e^t";
  spec.widthPx = 640;
  spec.heightPx = 480;
  PlotSeries s;
  s.name = "exp";
  for (int i = 0; i <= 20; ++i) {
    s.x.push_back(0.5 * i);
    s.y.push_back(std::exp(0.5 * i));
  }
  spec.series = {s};
  const auto dir = scratchFolder();
  spec.logY = true;
  writePlotPng(spec, dir / "log.png");
  expectNotBlank(dir / "log.png", 640, 480);
  // On a log axis e^t is a straight line, so the picture must differ from the linear-axis one.
  spec.logY = false;
  writePlotPng(spec, dir / "linear.png");
  EXPECT_GT(imageDifference(dir / "log.png", dir / "linear.png"), kBaselineTolerance);
}

TEST(XYPlot, AxisLimitsAndOneSidedLimitsRender) {
  forgetDisplay();
  PlotSpec spec = basicSpec();
  spec.logX = true;
  spec.series[0].x.erase(spec.series[0].x.begin()); // x = 0 has no place on a log axis
  spec.series[0].y.erase(spec.series[0].y.begin());
  spec.series[1].x.erase(spec.series[1].x.begin());
  spec.series[1].y.erase(spec.series[1].y.begin());
  spec.xMin = 0.1;
  spec.yMax = 150.0;
  const auto png = scratchFolder() / "limits.png";
  writePlotPng(spec, png);
  expectNotBlank(png, 900, 650);
}

TEST(XYPlot, BadSpecsThrowAndLeaveNoFile) {
  forgetDisplay();
  const auto dir = scratchFolder();
  const auto png = dir / "bad.png";
  const double nan = std::numeric_limits<double>::quiet_NaN();

  auto expectRejected = [&](const PlotSpec& spec, const char* what) {
    EXPECT_THROW(writePlotPng(spec, png), std::invalid_argument) << what;
    EXPECT_TRUE(folderIsEmpty(dir)) << what << ": something was left in " << dir;
  };

  PlotSpec mismatched = basicSpec();
  mismatched.series[1].y.pop_back();
  expectRejected(mismatched, "x and y of different lengths");

  PlotSpec withNan = basicSpec();
  withNan.series[0].y[3] = nan;
  expectRejected(withNan, "NaN in y");

  PlotSpec withInf = basicSpec();
  withInf.series[1].x[2] = std::numeric_limits<double>::infinity();
  expectRejected(withInf, "infinity in x");

  PlotSpec zeroOnLog = basicSpec();
  zeroOnLog.logY = true; // y = x^2 starts at 0
  expectRejected(zeroOnLog, "zero on a log axis");

  PlotSpec noSeries = basicSpec();
  noSeries.series.clear();
  expectRejected(noSeries, "no series");

  PlotSpec emptySeries = basicSpec();
  emptySeries.series[1].x.clear();
  emptySeries.series[1].y.clear();
  expectRejected(emptySeries, "series without points");

  PlotSpec emptyRange = basicSpec();
  emptyRange.xMin = 20.0; // above every x, and no xMax
  expectRejected(emptyRange, "empty axis range");

  // The message names the series and the fault in one line.
  try {
    writePlotPng(zeroOnLog, png);
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("x^2"), std::string::npos) << message;
    EXPECT_NE(message.find("logarithmic"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(XYPlot, MissingFolderThrowsWithoutCreatingIt) {
  forgetDisplay();
  const auto dir = scratchFolder() / "does-not-exist";
  EXPECT_THROW(writePlotPng(basicSpec(), dir / "plot.png"), std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(dir));
}

// ---- Backends (issue 12, item 5): pictures with no X server at all, and failures that are never silent.

namespace {

// Renders basicSpec() into `png` in a fresh process (a backend is settled once per process) with no
// DISPLAY and a PATH that holds no Xvfb, forcing `backend` ("" lets the program choose). The child exits
// 0 if it rendered with `expectBackend` and started no X server; the parent then compares the picture.
void renderInFreshProcess(const std::string& backend, const std::string& expectBackend,
                          const std::filesystem::path& png) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::filesystem::path emptyBin = png.parent_path() / "empty-bin";
  std::filesystem::create_directories(emptyBin);
  EXPECT_EXIT(
      {
        unsetenv("DISPLAY");
        setenv("PATH", emptyBin.c_str(), 1);
        if (backend.empty()) unsetenv("CEMENTSPH_RENDER_BACKEND");
        else setenv("CEMENTSPH_RENDER_BACKEND", backend.c_str(), 1);
        try {
          writePlotPng(basicSpec(), png);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "%s\n", e.what());
          std::exit(2);
        }
        const auto used = lastRenderBackend();
        const bool rightBackend = used && renderBackendName(*used) == expectBackend;
        std::exit(rightBackend && !VirtualDisplay::startedVirtualServer() ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
}

} // namespace

// The default path on a headless machine: OSMesa, no X server, and the same picture as the baseline
// (which was drawn through Xvfb + GLX, an independent GL path).
TEST(RenderBackendRegression, NoDisplayNoXvfbRendersBaselineWithOSMesa) {
  const auto png = scratchFolder() / "osmesa.png";
  renderInFreshProcess("", "osmesa", png);
  ASSERT_TRUE(std::filesystem::exists(png));
  expectMatchesBaseline(png, "xyplot_basic.png", kBaselineTolerance);
}

TEST(RenderBackendRegression, SurfacelessEglRendersBaseline) {
  const auto png = scratchFolder() / "egl.png";
  renderInFreshProcess("egl", "egl", png);
  ASSERT_TRUE(std::filesystem::exists(png));
  expectMatchesBaseline(png, "xyplot_basic.png", kBaselineTolerance);
}

// The fallback: an X display (a private Xvfb here, since DISPLAY is unset) still renders the baseline.
TEST(RenderBackendRegression, XFallbackRendersBaseline) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const auto png = scratchFolder() / "x.png";
  EXPECT_EXIT(
      {
        unsetenv("DISPLAY");
        setenv("CEMENTSPH_RENDER_BACKEND", "x", 1);
        writePlotPng(basicSpec(), png);
        const auto used = lastRenderBackend();
        std::exit(used == RenderBackend::XDisplay ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
  ASSERT_TRUE(std::filesystem::exists(png));
  expectMatchesBaseline(png, "xyplot_basic.png", kBaselineTolerance);
}

// A render that comes back black (here: a black background and nothing drawn, the look of a context
// that drew nothing) is a RenderFailure, and no picture is left behind.
TEST(RenderBackend, BlackRenderIsAnErrorAndWritesNothing) {
  forgetDisplay();
  const auto dir = scratchFolder();
  auto window = makeOffScreenRenderWindow(64, 48);
  auto renderer = vtkSmartPointer<vtkRenderer>::New();
  renderer->SetBackground(0.0, 0.0, 0.0);
  window->AddRenderer(renderer);
  try {
    writeWindowPng(window, dir / "black.png");
    ADD_FAILURE() << "a black render was written without an error";
  } catch (const RenderFailure& e) {
    EXPECT_NE(std::string(e.what()).find("all black"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(folderIsEmpty(dir));
  EXPECT_EQ(RenderFailure::exitCode, 3);
}

// The same window with a grey background is a picture: the check does not reject everything.
TEST(RenderBackend, GreyRenderIsWrittenWithItsColour) {
  forgetDisplay();
  const auto png = scratchFolder() / "grey.png";
  auto window = makeOffScreenRenderWindow(64, 48);
  auto renderer = vtkSmartPointer<vtkRenderer>::New();
  renderer->SetBackground(0.5, 0.5, 0.5);
  window->AddRenderer(renderer);
  writeWindowPng(window, png);
  const auto s = summarisePng(png);
  EXPECT_EQ(s.width, 64);
  EXPECT_EQ(s.height, 48);
  EXPECT_EQ(s.distinctColours, 1u);
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(png.string().c_str());
  reader->Update();
  // 0.5 of 255 is 127.5; GL rounds to 127 or 128.
  EXPECT_NEAR(reader->GetOutput()->GetScalarComponentAsDouble(10, 10, 0, 0), 127.5, 0.6);
}

TEST(RenderBackend, UnknownForcedBackendIsOneClearLine) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        setenv("CEMENTSPH_RENDER_BACKEND", "vulkan", 1);
        try {
          makeOffScreenRenderWindow(8, 8);
        } catch (const RenderFailure& e) {
          std::fprintf(stderr, "%s\n", e.what());
          std::exit(RenderFailure::exitCode);
        }
        std::exit(0);
      },
      ::testing::ExitedWithCode(3), "CEMENTSPH_RENDER_BACKEND is 'vulkan'; use osmesa, egl or x");
}
