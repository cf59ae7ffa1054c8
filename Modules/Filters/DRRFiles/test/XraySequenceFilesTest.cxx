// The X-ray sequence's files (XraySequenceFiles.h): the frame list read from an inject folder's sequence.json
// or from a list of volumes, against the values the test itself writes, and its refusals, each one line
// naming the file or option.
#include "cementsph/drr/XraySequenceFiles.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using cementsph::drr::readXrayFrameList;

class XraySequenceFiles : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("xray_sequence_files_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / name) << text; }
  // The message of the std::runtime_error that reading values throws ("" when it does not throw).
  std::string refusal(const std::vector<std::string>& values, const std::vector<double>& times = {}) {
    try {
      (void)readXrayFrameList(values, times, "--sequence");
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(XraySequenceFiles, AnInjectFolderGivesItsFramesTimesAndTip) {
  write("ct_0000.nrrd", "x");
  write("ct_0001.nrrd", "x");
  write("sequence.json", R"({"frames": [{"simulated_ct": "ct_0000.nrrd", "time_s": 0},
                                        {"simulated_ct": "ct_0001.nrrd", "time_s": 2.5}]})");
  write("scene.json", R"({"tip_mm": [1.5, -2, 30]})");
  const auto f = readXrayFrameList({dir_.string()}, {}, "--sequence");
  ASSERT_EQ(f.paths.size(), 2u);
  EXPECT_EQ(f.paths[1], (dir_ / "ct_0001.nrrd").string());
  EXPECT_EQ(f.timesS, (std::vector<double>{0.0, 2.5}));
  EXPECT_EQ(f.source, dir_.string());
  ASSERT_TRUE(f.tipMm.has_value());
  EXPECT_EQ(*f.tipMm, (cementsph::drr::Vec3{1.5, -2.0, 30.0}));
}

TEST_F(XraySequenceFiles, AListOfVolumesIsTimedZeroOneTwoUnlessTimesAreGiven) {
  const std::string a = (dir_ / "a.nrrd").string(), b = (dir_ / "b.nrrd").string(), c = (dir_ / "c.nrrd").string();
  for (const auto& p : {a, b, c}) std::ofstream(p) << "x";
  const auto f = readXrayFrameList({a, b, c}, {}, "--sequence");
  EXPECT_EQ(f.timesS, (std::vector<double>{0.0, 1.0, 2.0}));
  EXPECT_EQ(f.source, "list");
  EXPECT_FALSE(f.tipMm.has_value());
  EXPECT_EQ(readXrayFrameList({a, b, c}, {0.0, 0.5, 4.0}, "--sequence").timesS, (std::vector<double>{0.0, 0.5, 4.0}));
}

TEST_F(XraySequenceFiles, EachMalformedInputIsRefusedNamingTheFileOrOption) {
  const std::string a = (dir_ / "a.nrrd").string(), b = (dir_ / "b.nrrd").string();
  std::ofstream(a) << "x";
  std::ofstream(b) << "x";
  EXPECT_NE(refusal({dir_.string()}).find("no sequence.json"), std::string::npos);
  write("sequence.json", R"({"frames": [{"simulated_ct": "a.nrrd"}]})");
  EXPECT_NE(refusal({dir_.string()}).find("sequence.json: a frame lacks simulated_ct or time_s"), std::string::npos);
  write("sequence.json", "[1, 2]");
  EXPECT_NE(refusal({dir_.string()}).find("not a sequence list"), std::string::npos);
  EXPECT_NE(refusal({dir_.string()}, {0.0}).find("--sequence-times-s"), std::string::npos);
  EXPECT_NE(refusal({a, b}, {0.0}).find("--sequence-times-s: 1 times for 2 volumes"), std::string::npos);
  EXPECT_NE(refusal({a}).find("at least 2 frames"), std::string::npos);
  EXPECT_NE(refusal({a, b}, {1.0, 1.0}).find("frame times must increase (1 s after 1 s)"), std::string::npos);
  EXPECT_NE(refusal({a, (dir_ / "missing.nrrd").string()}).find("missing.nrrd: no such file"), std::string::npos);
}

TEST(XraySequenceCsv, AComparisonRowLeavesTheUnmatchedSideEmpty) {
  // No frames are needed for the header and the rows of pairs that matched nothing on either side.
  cementsph::drr::XraySequenceOptions options;
  const cementsph::drr::XraySequence empty(options);
  cementsph::drr::XrayComparison comparison;
  comparison.pairs.push_back({1.25, std::nullopt, std::nullopt, std::nullopt, std::nullopt});
  EXPECT_EQ(cementsph::drr::xraySequenceCsv(empty, &empty, &comparison),
            "time_s,projected_area_mm2,detector_area_mm2,cement_pixels,reference_time_s,"
            "reference_projected_area_mm2,reference_detector_area_mm2,reference_cement_pixels,dice,iou\n"
            "1.25,,,,,,,,,\n");
  EXPECT_EQ(cementsph::drr::xraySequenceCsv(empty, nullptr, nullptr),
            "time_s,projected_area_mm2,detector_area_mm2,cement_pixels\n");
}

} // namespace
