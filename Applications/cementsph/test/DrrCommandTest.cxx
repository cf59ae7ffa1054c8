// The `cementsph drr` command, run as a user would: drr.nrrd holds the filter's numbers with the
// detector's geometry, drr.png is an 8-bit picture of the same size drawn dense-dark; bad input gives one
// clear line on stderr, a non-zero exit and no output at all.
#include "DRRTestSupport.h"
#include "ProgramRun.h"
#include "cementsph/drr/vtkDRRFilter.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <itkImageFileReader.h>
#include <itkNrrdImageIO.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace cementsph::drrtest;
using cementsph::testing::ProgramRun;

namespace {

// `cementsph drr ARGS...`
ProgramRun drr(std::vector<std::string> args) {
  args.insert(args.begin(), "drr");
  return cementsph::testing::runProgram(CEMENTSPH_EXE, args);
}

class DrrCommand : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    // One directory per process: ctest runs each test in its own process, possibly in parallel (-j).
    dir_ = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / ("drr-command-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    VolumeGrid grid = centredGrid({41, 37, 33}, {1.0, 1.1, 1.2}, {5.0, -3.0, 2.0});
    // A rotated direction matrix too: the file must carry it through to the projection.
    const double c = std::cos(0.3), s = std::sin(0.3);
    grid.direction = {c, -s, 0, s, c, 0, 0, 0, 1};
    volume_ = voxelise(grid, balls({{{5.1, -3.2, 2.3}, 12.3, 900.0}, {{9.2, 1.1, 6.3}, 4.1, 3000.0}}));
    cementsph::imaging::writeVolume(cementsph::imaging::imageFromVtk(volume_), (dir_ / "ct.nrrd").string());
  }
  static void TearDownTestSuite() {
    volume_ = nullptr;
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  static fs::path dir_;
  static vtkSmartPointer<vtkImageData> volume_;
};
fs::path DrrCommand::dir_;
vtkSmartPointer<vtkImageData> DrrCommand::volume_;

} // namespace

TEST_F(DrrCommand, WritesTheFilterNumbersAndAPicture) {
  const fs::path out = dir_ / "ok";
  const ProgramRun r = drr({"--volume", (dir_ / "ct.nrrd").string(), "--out", out.string(), "--detector-pixels",
                            "48,64", "--detector-size-mm", "96,128", "--sad-mm", "900", "--sid-mm", "1400",
                            "--isocenter-mm", "4,-2,1", "--gantry-angle-deg", "25", "--threads", "2"});
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("wrote"), std::string::npos);
  ASSERT_TRUE(fs::exists(out / "drr.nrrd"));
  ASSERT_TRUE(fs::exists(out / "drr.png"));
  for (const auto& e : fs::directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();

  vtkNew<vtkDRRFilter> f;
  f->SetInputData(volume_);
  f->SetDetectorRows(48);
  f->SetDetectorColumns(64);
  f->SetDetectorHeight(96);
  f->SetDetectorWidth(128);
  f->SetSourceAxisDistance(900);
  f->SetSourceImageDistance(1400);
  f->SetIsocenter(4, -2, 1);
  f->SetGantryAngle(25);
  f->Update();
  const float* expected = static_cast<const float*>(f->GetOutput()->GetScalarPointer());

  using Image = itk::Image<float, 3>;
  auto reader = itk::ImageFileReader<Image>::New();
  reader->SetImageIO(itk::NrrdImageIO::New());
  reader->SetFileName((out / "drr.nrrd").string());
  reader->Update();
  const Image* drr = reader->GetOutput();
  const auto size = drr->GetLargestPossibleRegion().GetSize();
  ASSERT_EQ(size[0], 64u);
  ASSERT_EQ(size[1], 48u);
  ASSERT_EQ(size[2], 1u);
  EXPECT_NEAR(drr->GetSpacing()[0], 2.0, 1e-9);
  EXPECT_NEAR(drr->GetSpacing()[1], 2.0, 1e-9);
  EXPECT_NEAR(drr->GetOrigin()[0], -63.0, 1e-9); // detector centre at (0, 0)
  double maxValue = 0.0;
  for (std::size_t k = 0; k < 64 * 48; ++k) {
    ASSERT_NEAR(drr->GetBufferPointer()[k], expected[k], 1e-6) << k;
    maxValue = std::max(maxValue, static_cast<double>(expected[k]));
  }
  EXPECT_GT(maxValue, 0.05); // the object is in view

  vtkNew<vtkPNGReader> png;
  png->SetFileName((out / "drr.png").string().c_str());
  png->Update();
  int dims[3];
  png->GetOutput()->GetDimensions(dims);
  EXPECT_EQ(dims[0], 64);
  EXPECT_EQ(dims[1], 48);
  EXPECT_EQ(png->GetOutput()->GetScalarType(), VTK_UNSIGNED_CHAR);
  EXPECT_EQ(png->GetOutput()->GetScalarRange()[1], 255.0);
  // Dense matter dark, the convention of every X-ray picture the program writes (xray_frames.png too): grey =
  // 255 (1 - value / largest value), from the filter's numbers; 1 grey level for the rounding to 8 bits.
  const auto* grey = static_cast<const unsigned char*>(png->GetOutput()->GetScalarPointer());
  const int components = png->GetOutput()->GetNumberOfScalarComponents();
  for (std::size_t k = 0; k < 64 * 48; ++k)
    ASSERT_NEAR(double(grey[k * std::size_t(components)]), 255.0 * (1.0 - double(expected[k]) / maxValue), 1.0) << k;
}

TEST_F(DrrCommand, ParallelBeamRuns) {
  const ProgramRun r = drr({"--volume", (dir_ / "ct.nrrd").string(), "--out", (dir_ / "par").string(), "--parallel",
                            "--detector-pixels", "20,20", "--detector-size-mm", "60,60"});
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("parallel beam"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir_ / "par" / "drr.nrrd"));
}

TEST_F(DrrCommand, BadInputIsOneLineNonZeroAndNoOutput) {
  const std::string ct = (dir_ / "ct.nrrd").string();
  const struct {
    std::vector<std::string> args;
    std::string message;
  } cases[] = {
      {{"--volume", (dir_ / "missing.nrrd").string()}, "missing.nrrd"},
      {{"--volume", ct, "--sad-mm", "1000", "--sid-mm", "800"}, "source-image distance"},
      {{"--volume", ct, "--detector-pixels", "0,10"}, "at least 1x1 pixels"},
      {{"--volume", ct, "--detector-size-mm", "100,-5"}, "detector size must be positive"},
      {{"--volume", ct, "--threads", "-1"}, "--threads"},
  };
  int n = 0;
  for (const auto& c : cases) {
    const fs::path out = dir_ / ("bad" + std::to_string(n++));
    std::vector<std::string> args = c.args;
    args.insert(args.end(), {"--out", out.string()});
    const ProgramRun r = drr(args);
    EXPECT_NE(r.exitCode, 0) << c.message;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.rfind("cementsph drr: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.message;
  }
}

// `cementsph` is a launcher that runs libexec/cementsph/cementsph-drr (or -all) in its place. Without
// them beside it, it says which program it could not run, in one line, and exits 2 (a failed run).
TEST(CementsphLauncher, MissingProgramsAreOneClearLine) {
  const fs::path alone = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / ("launcher-alone-" + std::to_string(::getpid()));
  fs::remove_all(alone);
  fs::create_directories(alone / "bin");
  fs::copy_file(CEMENTSPH_EXE, alone / "bin" / "cementsph");
  const ProgramRun r = cementsph::testing::runProgram((alone / "bin" / "cementsph").string(), std::vector<std::string>{"drr", "--help"});
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.err.find("cannot run " + (alone / "bin" / "../libexec/cementsph/cementsph-drr").string()),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  fs::remove_all(alone);
}
