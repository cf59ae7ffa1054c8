// `cementsph xray`, run as a user would. A list of three volumes (soft tissue, then a cement cylinder of
// radius 3 mm and of radius 5 mm along the beam, 6.5 mm long, its ends on voxel faces) at 0, 1.5 and 3 s,
// thresholded at half the cylinder's excess line integral (9.75 mm of water), must give projected areas
// pi r^2 at the isocentre (within 3 %: 0.25 mm pixels at the isocentre on 6 and 10 mm discs); the written
// DRRs must differ by the cylinder's excess line integral L dmu / 10 = 0.0429 on its axis (within 1 %;
// the axis crosses whole voxels only, so the partial volumes are exact there); against itself the
// sequence gives Dice = IoU = 1 in every row. An inject folder (scene key simulated_ct_snapshots) is read
// through its sequence.json. Bad input: one line on stderr naming the input, exit 1, no output folder and no
// staging folder left behind.
#include "DRRTestSupport.h"
#include "ProgramRun.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <itkImageFileReader.h>
#include <itkNrrdImageIO.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace cementsph::drrtest;
using cementsph::testing::ProgramRun;

namespace {

constexpr double kPi = 3.14159265358979323846;

ProgramRun runCementsph(std::vector<std::string> args) {
  setenv("OMP_NUM_THREADS", "1", 1);
  return cementsph::testing::runProgram(CEMENTSPH_EXE, args);
}

std::vector<std::vector<std::string>> readCsv(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, ',')) fields.push_back(f);
    if (!line.empty() && line.back() == ',') fields.emplace_back();
    rows.push_back(fields);
  }
  return rows;
}

double pixelOf(const fs::path& nrrd, std::size_t i, std::size_t j) {
  using Image = itk::Image<float, 3>;
  auto reader = itk::ImageFileReader<Image>::New();
  reader->SetImageIO(itk::NrrdImageIO::New());
  reader->SetFileName(nrrd.string());
  reader->Update();
  Image::IndexType index;
  index[0] = long(i);
  index[1] = long(j);
  index[2] = 0;
  return reader->GetOutput()->GetPixel(index);
}

class XrayCommand : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    dir_ = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / ("xray-command-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // 41^3 voxels of 0.5 mm about the origin; the cylinder's axis off the voxel lattice (see XraySequenceTest).
    VolumeGrid grid = centredGrid({41, 41, 41}, {0.5, 0.5, 0.5}, {0, 0, 0});
    grid.subsamples = 5;
    for (int k = 0; k < 3; ++k) {
      const double radius = k == 0 ? 0.0 : (k == 1 ? 3.0 : 5.0);
      const auto volume = voxelise(grid, [radius](const Vec3& p) {
        const double y = p[1] - 0.17, z = p[2] - 0.23;
        if (std::abs(p[0]) <= 3.25 && y * y + z * z <= radius * radius) return 3040.0;
        return p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= 9.5 * 9.5 ? 40.0 : -1000.0;
      });
      const fs::path path = dir_ / ("frame" + std::to_string(k) + ".nrrd");
      cementsph::imaging::writeVolume(cementsph::imaging::imageFromVtk(volume), path.string());
      frames_ += (k ? "," : "") + path.string();
    }
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  // The common arguments: the list, its times, a 128 x 128 detector of 48 mm (0.25 mm at the isocentre),
  // and the half-cylinder threshold (6.5 mm x 3 / 2 mm of water).
  static std::vector<std::string> listArgs(const fs::path& out) {
    return {"xray", "--sequence", frames_, "--sequence-times-s", "0,1.5,3", "--out", out.string(), "--detector-pixels",
            "128,128", "--detector-size-mm", "48,48", "--cement-threshold-water-mm", "9.75"};
  }
  static fs::path dir_;
  static std::string frames_;
};
fs::path XrayCommand::dir_;
std::string XrayCommand::frames_;

} // namespace

TEST_F(XrayCommand, ListOfVolumesGivesTheCylinderAreasAndTheFiles) {
  const fs::path out = dir_ / "list";
  const ProgramRun r = runCementsph(listArgs(out));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (const char* f : {"sequence.csv", "metrics.json", "xray_frames.png", "projected_area.png", "sequence_drr_0000.nrrd",
                        "sequence_drr_0000.png", "sequence_drr_0002.nrrd", "sequence_drr_0002.png"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path(); // staging folder gone

  const auto rows = readCsv(out / "sequence.csv");
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"time_s", "projected_area_mm2", "detector_area_mm2", "cement_pixels"}));
  EXPECT_EQ(std::stod(rows[1][1]), 0.0);
  const double expected[] = {0.0, kPi * 9.0, kPi * 25.0};
  for (int k = 1; k <= 2; ++k) {
    EXPECT_DOUBLE_EQ(std::stod(rows[k + 1][0]), 1.5 * k);
    const double area = std::stod(rows[k + 1][1]);
    std::cout << "frame " << k << ": " << area << " mm^2 (pi r^2 = " << expected[k] << ")\n";
    EXPECT_NEAR(area, expected[k], 0.03 * expected[k]);
    EXPECT_NEAR(std::stod(rows[k + 1][2]), area * 1.5 * 1.5, 1e-6 * area);
  }
  // The written DRRs: on the axis the last frame exceeds the first by L dmu / 10 = 6.5 x 0.066 / 10.
  const double onAxis = pixelOf(out / "sequence_drr_0002.nrrd", 64, 64) - pixelOf(out / "sequence_drr_0000.nrrd", 64, 64);
  EXPECT_NEAR(onAxis, 0.0429, 0.01 * 0.0429);

  std::ifstream in(out / "metrics.json");
  const auto m = nlohmann::json::parse(in);
  EXPECT_EQ(m.at("frames").get<int>(), 3);
  EXPECT_DOUBLE_EQ(m.at("segmentation").at("cement_threshold_drr").get<double>(), 9.75 * 0.0022);
  EXPECT_FALSE(m.at("geometry").at("detector_fitted_to_first_frame").get<bool>());
  EXPECT_TRUE(m.at("segmentation").at("injection_point_mm").is_null());
  EXPECT_NE(r.out.find("final projected cement area"), std::string::npos) << r.out;
}

TEST_F(XrayCommand, AgainstItselfEveryFrameHasDiceOne) {
  const fs::path out = dir_ / "self";
  std::vector<std::string> args = listArgs(out);
  args.insert(args.end(), {"--reference", frames_, "--reference-times-s", "0,1.5,3", "--no-pictures"});
  const ProgramRun r = runCementsph(args);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_FALSE(fs::exists(out / "xray_frames.png"));
  EXPECT_TRUE(fs::exists(out / "reference_drr_0002.nrrd"));
  const auto rows = readCsv(out / "sequence.csv");
  ASSERT_EQ(rows.size(), 4u);
  ASSERT_EQ(rows[0].size(), 10u);
  EXPECT_EQ(rows[0][8], "dice");
  EXPECT_EQ(rows[0][9], "iou");
  for (std::size_t k = 1; k < rows.size(); ++k) {
    EXPECT_EQ(std::stod(rows[k][8]), 1.0) << k;
    EXPECT_EQ(std::stod(rows[k][9]), 1.0) << k;
    EXPECT_EQ(rows[k][1], rows[k][5]) << k; // same areas
  }
  std::ifstream in(out / "metrics.json");
  const auto m = nlohmann::json::parse(in);
  EXPECT_EQ(m.at("final_frame").at("dice").get<double>(), 1.0);
  EXPECT_EQ(m.at("matched_frames").get<int>(), 3);
}

TEST_F(XrayCommand, ReferenceWithOtherTimesIsMatchedByTime) {
  const fs::path out = dir_ / "times";
  std::vector<std::string> args = listArgs(out);
  // The reference's frames at 0 and 3.2 s: 3.2 s matches the 3 s frame (tolerance 0.75 s), 1.5 s matches nothing.
  const std::string first = frames_.substr(0, frames_.find(',')), last = frames_.substr(frames_.rfind(',') + 1);
  args.insert(args.end(), {"--reference", first + "," + last, "--reference-times-s", "0,3.2", "--no-pictures"});
  const ProgramRun r = runCementsph(args);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto rows = readCsv(out / "sequence.csv");
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[2][4], ""); // no reference frame at 1.5 s: empty fields, not NaN
  EXPECT_EQ(rows[2][8], "");
  EXPECT_DOUBLE_EQ(std::stod(rows[3][4]), 3.2);
  EXPECT_EQ(std::stod(rows[3][8]), 1.0);
}

TEST_F(XrayCommand, InjectFolderIsReadThroughItsSequenceList) {
  // A fake inject folder: sequence.json naming the frames (relative), and scene.json with tip_mm.
  const fs::path folder = dir_ / "inject";
  fs::create_directories(folder);
  std::stringstream names(frames_);
  std::string path;
  nlohmann::json frames = nlohmann::json::array();
  for (int k = 0; std::getline(names, path, ','); ++k) {
    fs::copy_file(path, folder / ("simulated_ct_" + std::to_string(k) + ".nrrd"), fs::copy_options::overwrite_existing);
    frames.push_back({{"index", k}, {"time_s", 2.0 * k}, {"simulated_ct", "simulated_ct_" + std::to_string(k) + ".nrrd"}});
  }
  std::ofstream(folder / "sequence.json") << nlohmann::json{{"frames", frames}}.dump();
  std::ofstream(folder / "scene.json") << R"({"tip_mm": [0, 0.17, 0.23]})";
  const fs::path out = dir_ / "from-inject";
  const ProgramRun r = runCementsph({"xray", "--sequence", folder.string(), "--out", out.string(), "--no-pictures",
                                  "--cement-threshold-water-mm", "9.75"});
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto rows = readCsv(out / "sequence.csv");
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_DOUBLE_EQ(std::stod(rows[3][0]), 4.0);
  EXPECT_NEAR(std::stod(rows[3][1]), kPi * 25.0, 0.03 * kPi * 25.0); // fitted detector: pixels of ~0.12 mm
  std::ifstream in(out / "metrics.json");
  const auto m = nlohmann::json::parse(in);
  EXPECT_TRUE(m.at("geometry").at("detector_fitted_to_first_frame").get<bool>());
  EXPECT_EQ(m.at("segmentation").at("injection_point_mm"), nlohmann::json::parse("[0, 0.17, 0.23]"));
}

TEST_F(XrayCommand, HelpListsTheSharedGeometryOptions) {
  const ProgramRun r = runCementsph({"xray", "--help"});
  EXPECT_EQ(r.exitCode, 0);
  for (const char* option : {"--sequence", "--reference", "--out", "--sad-mm", "--sid-mm", "--detector-pixels",
                             "--detector-size-mm", "--isocenter-mm", "--gantry-angle-deg", "--parallel",
                             "--cement-threshold-water-mm", "--match-tolerance-s", "--injection-point-mm"})
    EXPECT_NE(r.out.find(option), std::string::npos) << option;
}

TEST_F(XrayCommand, BadInputIsOneLineNonZeroAndNoOutput) {
  const std::string first = frames_.substr(0, frames_.find(','));
  fs::create_directories(dir_ / "not-inject");
  const struct {
    std::vector<std::string> args;
    std::string message;
  } cases[] = {
      {{"--sequence", first + "," + (dir_ / "missing.nrrd").string()}, "missing.nrrd: no such file"},
      {{"--sequence", first}, "at least 2 frames"},
      {{"--sequence", (dir_ / "not-inject").string()}, "no sequence.json"},
      {{"--sequence", frames_, "--sequence-times-s", "0,1"}, "2 times for 3 volumes"},
      {{"--sequence", frames_, "--sequence-times-s", "0,2,1"}, "frame times must increase"},
      {{"--sequence", frames_, "--cement-threshold-water-mm", "-1"}, "--cement-threshold-water-mm"},
      {{"--sequence", frames_, "--sad-mm", "1000", "--sid-mm", "900"}, "source-image distance"},
      {{"--sequence", frames_, "--reference", first}, "--reference: a sequence needs at least 2 frames"},
      {{"--sequence", frames_, "--reference-times-s", "0,1"}, "--reference-times-s needs --reference"},
  };
  int n = 0;
  for (const auto& c : cases) {
    const fs::path out = dir_ / ("bad" + std::to_string(n++)) / "out";
    std::vector<std::string> args{"xray"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    args.insert(args.end(), {"--out", out.string()});
    const ProgramRun r = runCementsph(args);
    EXPECT_EQ(r.exitCode, 1) << c.message;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.rfind("cementsph xray: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out.parent_path())) << c.message; // not even the parent it would have created
  }
}

TEST_F(XrayCommand, AFolderInTheWayOfAnOutputFileMovesNothing) {
  const fs::path out = dir_ / "in-the-way";
  fs::create_directories(out / "sequence.csv");
  const ProgramRun r = runCementsph(listArgs(out));
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("sequence.csv is a folder; nothing was written"), std::string::npos) << r.err;
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(out)) ++entries, (void)e;
  EXPECT_EQ(entries, 1u); // only the folder that was there
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST_F(XrayCommand, AnEarlierRunsExtraFramesAreRemoved) {
  const fs::path out = dir_ / "rerun";
  fs::create_directories(out);
  // A frame number the new run does not make, as a longer earlier sequence would have left it.
  for (const char* stale : {"sequence_drr_0099.nrrd", "sequence_drr_0099.png"}) std::ofstream(out / stale) << "old";
  std::ofstream(out / "notes.txt") << "mine"; // not ours: kept
  const ProgramRun r = runCementsph(listArgs(out));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_FALSE(fs::exists(out / "sequence_drr_0099.nrrd"));
  EXPECT_FALSE(fs::exists(out / "sequence_drr_0099.png"));
  EXPECT_TRUE(fs::exists(out / "sequence_drr_0000.nrrd"));
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
}
