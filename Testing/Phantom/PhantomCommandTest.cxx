// cementsph phantom end to end: a small pair, truth.json, determinism of pre.nrrd; bad input.
#include "ProgramRun.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using cementsph::testing::runProgram;

namespace {
fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "phantom-command" / name;
  fs::remove_all(p);
  fs::create_directories(p.parent_path());
  return p;
}
} // namespace

TEST(PhantomCommand, WritesAPairAndTruth) {
  const fs::path out = scratch("pair");
  const auto r = runProgram(CEMENTSPH_EXECUTABLE, {"phantom", "--out", out.string(), "--size-mm", "14", "--shell-mm",
                                                   "2", "--cell-size-mm", "3.5", "--volume-ml", "0.1", "--quiet",
                                                   "--threads", "1"});
  ASSERT_EQ(r.exitCode, 0) << r.err;
  ASSERT_TRUE(fs::exists(out / "pre.nrrd"));
  ASSERT_TRUE(fs::exists(out / "post.nrrd"));
  std::ifstream in(out / "truth.json");
  const nlohmann::json t = nlohmann::json::parse(in);
  EXPECT_NEAR(t["foam"]["realised_porosity"].get<double>(), 0.8, 0.03);
  EXPECT_EQ(t["foam"]["seed"].get<int>(), 1);
  EXPECT_EQ(t["misalignment"]["rotation_deg"].size(), 3u);
  EXPECT_EQ(t["injection"]["tip_mm"].size(), 3u);
  EXPECT_NEAR(t["injection"]["volume_injected_ml"].get<double>(), 0.1, 0.005); // whole particles
  EXPECT_GT(t["injection"]["cement_voxels"].get<int>(), 0);
  const auto pre = cementsph::imaging::readVolume((out / "pre.nrrd").string());
  const auto post = cementsph::imaging::readVolume((out / "post.nrrd").string());
  EXPECT_TRUE(cementsph::imaging::geometryOf(pre).sameGrid(cementsph::imaging::geometryOf(post)));
  float maxPost = -1e9f, maxPre = -1e9f;
  for (std::size_t i = 0; i < pre->GetLargestPossibleRegion().GetNumberOfPixels(); ++i) {
    maxPre = std::max(maxPre, pre->GetBufferPointer()[i]);
    maxPost = std::max(maxPost, post->GetBufferPointer()[i]);
  }
  EXPECT_LT(maxPre, 1000.0f);
  EXPECT_GT(maxPost, 2000.0f); // cement
  // The same seed again: an identical pre CT.
  const fs::path again = scratch("again");
  const auto r2 = runProgram(CEMENTSPH_EXECUTABLE, {"phantom", "--out", again.string(), "--size-mm", "14", "--shell-mm",
                                                    "2", "--cell-size-mm", "3.5", "--no-post", "--quiet"});
  ASSERT_EQ(r2.exitCode, 0) << r2.err;
  EXPECT_FALSE(fs::exists(again / "post.nrrd"));
  const auto pre2 = cementsph::imaging::readVolume((again / "pre.nrrd").string());
  for (std::size_t i = 0; i < pre->GetLargestPossibleRegion().GetNumberOfPixels(); ++i)
    ASSERT_EQ(pre->GetBufferPointer()[i], pre2->GetBufferPointer()[i]);
}

TEST(PhantomCommand, BadInputIsOneLineExitOneAndNoOutput) {
  const std::vector<std::vector<std::string>> bad = {
      {"--porosity", "1.5"},         {"--cell-size-mm", "-2"},        {"--porosity", "0.7", "--strut-thickness-mm", "0.4"},
      {"--size-mm", "10,10"},         {"--noise-hu", "-3"},           {"--volume-ml", "0"},
      {"--viscosity-pa-s", "-1"},     {"--shell-mm", "nan"}};
  for (const auto& extra : bad) {
    const fs::path out = scratch("bad");
    std::vector<std::string> args{"phantom", "--out", out.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = runProgram(CEMENTSPH_EXECUTABLE, args);
    EXPECT_EQ(r.exitCode, 1) << extra[0] << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_FALSE(fs::exists(out)) << extra[0];
  }
}

TEST(PhantomCommand, PostDicomHoldsThePostCt) {
  const fs::path out = scratch("dicom");
  const auto r = runProgram(CEMENTSPH_EXECUTABLE, {"phantom", "--out", out.string(), "--size-mm", "10", "--volume-ml",
                                                   "0.05", "--post-dicom", "--quiet", "--threads", "1"});
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto post = cementsph::imaging::readVolume((out / "post.nrrd").string());
  const auto dicom = cementsph::imaging::readVolume((out / "post_dicom").string());
  ASSERT_TRUE(cementsph::imaging::geometryOf(post).sameGrid(cementsph::imaging::geometryOf(dicom)));
  for (std::size_t i = 0; i < post->GetLargestPossibleRegion().GetNumberOfPixels(); ++i)
    ASSERT_NEAR(post->GetBufferPointer()[i], dicom->GetBufferPointer()[i], 0.5) << i; // integer HU in both
}
