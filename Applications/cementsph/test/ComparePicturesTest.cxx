// `cementsph compare` on Data/compare-example without a display: the Fig. 11 and Fig. 7 pictures appear
// next to metrics.json, --no-pictures leaves them out, and a picture that cannot be written costs the
// exit status (3) but not the metrics.
#include "ProgramRun.h"
#include "RenderingTestSupport.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using cementsph::rendering::test::forgetDisplay;
using cementsph::rendering::test::scratchFolder;
using cementsph::rendering::test::summarisePng;
using cementsph::testing::runProgram;

namespace {

std::vector<std::string> compareArgs(const fs::path& out) {
  const fs::path data = fs::path(CEMENTSPH_TEST_DATA_DIR) / "compare-example";
  return {"compare",
          "--pre", (data / "pre.nrrd").string(),
          "--post", (data / "post_dicom").string(),
          "--simulated", (data / "simulated.nrrd").string(),
          "--injection-point-mm", "15.805,13.805,14.75",
          "--out", out.string()};
}

} // namespace

TEST(ComparePictures, WritesSlicesAndSurfacesHeadless) {
  forgetDisplay();
  const fs::path out = scratchFolder() / "out";
  const auto r = runProgram(CEMENTSPH_EXECUTABLE, compareArgs(out));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / "metrics.json"));
  const auto slices = summarisePng(out / "slices.png");
  EXPECT_GT(slices.width, 0);
  EXPECT_GT(slices.nonWhiteFraction, 0.5); // mostly CT pixels
  const auto surfaces = summarisePng(out / "surfaces.png");
  EXPECT_EQ(surfaces.width, 1500);
  EXPECT_EQ(surfaces.height, 560);
  EXPECT_GT(surfaces.distinctColours, 50u);
  // metrics.json names the backend that drew them; forced to OSMesa, it says so.
  auto backendOf = [](const fs::path& metrics) {
    std::ifstream in(metrics);
    return nlohmann::json::parse(in).value("render_backend", std::string("absent"));
  };
  const std::string backend = backendOf(out / "metrics.json");
  EXPECT_TRUE(backend == "osmesa" || backend == "egl" || backend == "x") << backend;
  setenv("CEMENTSPH_RENDER_BACKEND", "osmesa", 1);
  const fs::path forced = scratchFolder() / "forced";
  const auto f = runProgram(CEMENTSPH_EXECUTABLE, compareArgs(forced));
  unsetenv("CEMENTSPH_RENDER_BACKEND");
  ASSERT_EQ(f.exitCode, 0) << f.err;
  EXPECT_EQ(backendOf(forced / "metrics.json"), "osmesa");
}

TEST(ComparePictures, NoPicturesFlagWritesNone) {
  forgetDisplay();
  const fs::path out = scratchFolder() / "out";
  auto args = compareArgs(out);
  args.push_back("--no-pictures");
  const auto r = runProgram(CEMENTSPH_EXECUTABLE, args);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / "metrics.json"));
  EXPECT_FALSE(fs::exists(out / "slices.png"));
  EXPECT_FALSE(fs::exists(out / "surfaces.png"));
}

TEST(ComparePictures, FailedPictureKeepsMetricsAndExitsThree) {
  forgetDisplay();
  const fs::path out = scratchFolder() / "out";
  fs::create_directories(out / "slices.png" / "blocker"); // a non-empty folder where the PNG should go
  const auto r = runProgram(CEMENTSPH_EXECUTABLE, compareArgs(out));
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_TRUE(fs::exists(out / "metrics.json"));
  EXPECT_NE(r.err.find("picture slices.png not written"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(out / "surfaces.png")); // one failed picture does not stop the other
}

// No OpenGL to be had (here: a backend that does not exist is forced) fails the GL picture, surfaces.png,
// in one line and exit 3; the numbers and the picture composed without GL (slices.png) are written.
TEST(ComparePictures, NoOpenGLIsAFailedPictureExitThree) {
  // No GL context to be had: the X backend forced, no display, and no Xvfb on the PATH to start one. (A
  // misspelt backend is refused at the start instead: CementsphCommand.AMisspeltRenderBackendIsRefusedBeforeAnyWork.)
  forgetDisplay();
  const fs::path out = scratchFolder() / "out";
  const std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("CEMENTSPH_RENDER_BACKEND", "x", 1);
  setenv("PATH", "/nonexistent-cementsph-test", 1);
  const auto r = runProgram(CEMENTSPH_EXECUTABLE, compareArgs(out));
  setenv("PATH", path.c_str(), 1);
  unsetenv("CEMENTSPH_RENDER_BACKEND");
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_TRUE(fs::exists(out / "metrics.json"));
  EXPECT_FALSE(fs::exists(out / "surfaces.png"));
  EXPECT_NE(r.err.find("picture surfaces.png not written"), std::string::npos) << r.err;
}

// With CEMENTSPH_VERBOSE the program names the backend that drew its pictures; headless, that is OSMesa.
TEST(ComparePictures, VerboseNamesTheBackend) {
  forgetDisplay();
  const fs::path out = scratchFolder() / "out";
  setenv("CEMENTSPH_VERBOSE", "1", 1);
  const auto r = runProgram(CEMENTSPH_EXECUTABLE, compareArgs(out));
  unsetenv("CEMENTSPH_VERBOSE");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("pictures are drawn with osmesa"), std::string::npos) << r.err;
}
