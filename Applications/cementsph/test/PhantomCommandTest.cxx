// cementsph phantom end to end: a small pair, truth.json, determinism of pre.nrrd; bad input.
#include "ProgramRun.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
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

// The vertebra's anatomy variant through the command (issue 20): what the CT shows against the option values.
// Layout from VertebraPhantom.h (not from the generator's code): 1 x 1 x 1.5 mm voxels, origin at the first
// voxel centre, the body's centre at (field_x / 2, 15 + 6, field_z / 2) = (32, 21, 22.5) mm in the default
// 64 x 70 x 45 mm field, half height 12.5 mm. With --noise-hu 0 a voxel wholly inside a disc is exactly
// disc_hu (80) and one wholly inside the fat exactly marrow_fat_hu (-30): every other tissue or mix is another
// value (soft tissue 20, trabecular >= 90, cortex 700; partial volume in 27ths).
namespace {
cementsph::imaging::ImageType::Pointer vertebra(const fs::path& out, const std::vector<std::string>& extra) {
  std::vector<std::string> args{"phantom", "--kind", "vertebra", "--out", out.string(), "--noise-hu", "0"};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto r = runProgram(CEMENTSPH_EXECUTABLE, args);
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return cementsph::imaging::readVolume((out / "pre.nrrd").string());
}

// Voxels of exactly `hu` (to rounding) in the column through the body's centre, above (z > 22.5 mm) the centre.
int columnVoxelsAbove(const cementsph::imaging::ImageType* ct, float hu) {
  const int i = 32, j = 21; // x = 32 mm, y = 21 mm
  int n = 0;
  const auto size = ct->GetLargestPossibleRegion().GetSize();
  for (int k = 0; k < int(size[2]); ++k)
    if (k * 1.5 > 22.5 && std::abs(ct->GetPixel({i, j, k}) - hu) < 0.5f) ++n;
  return n;
}

int voxelsOf(const cementsph::imaging::ImageType* ct, float hu) {
  int n = 0;
  for (std::size_t v = 0; v < ct->GetLargestPossibleRegion().GetNumberOfPixels(); ++v)
    if (std::abs(ct->GetBufferPointer()[v] - hu) < 0.5f) ++n;
  return n;
}
} // namespace

TEST(PhantomCommand, VertebraDiscHeightIsTheOptionWithinAVoxel) {
  // n whole voxels of 1.5 mm fit in a disc of height h when n * 1.5 <= h < (n + 2) * 1.5: (n + 1) * 1.5 is h to
  // within one voxel.
  const auto ct = vertebra(scratch("vertebra-disc"), {"--disc-height-mm", "6"});
  const int n = columnVoxelsAbove(ct, 80.0f);
  EXPECT_NEAR((n + 1) * 1.5, 6.0, 1.5) << n << " whole disc voxels";
  const auto plain = vertebra(scratch("vertebra-plain"), {});
  EXPECT_EQ(columnVoxelsAbove(plain, 80.0f), 0); // no disc without the option
}

TEST(PhantomCommand, VertebraMarrowFatAndVeinAppearOnlyWhenAsked) {
  // The voxels wholly inside a fat sphere of radius 5 mm lie inside it and hold the sphere of radius 5 - d
  // (d = half the voxel diagonal, sqrt(1 + 1 + 2.25) / 2 mm): their volume is between the two spheres'.
  const auto ct = vertebra(scratch("vertebra-fat"), {"--marrow-fat-radius-mm", "5", "--vein-radius-mm", "2"});
  const double fatMm3 = voxelsOf(ct, -30.0f) * 1.5, pi = 3.14159265358979;
  const double d = std::sqrt(1 + 1 + 2.25) / 2;
  EXPECT_LE(fatMm3, 4.0 / 3.0 * pi * 125.0);
  EXPECT_GE(fatMm3, 4.0 / 3.0 * pi * std::pow(5.0 - d, 3));
  EXPECT_GT(voxelsOf(ct, 60.0f), 0); // blood: the vein
  const auto plain = vertebra(scratch("vertebra-nofat"), {});
  EXPECT_EQ(voxelsOf(plain, -30.0f), 0);
  EXPECT_EQ(voxelsOf(plain, 60.0f), 0);
}

TEST(PhantomCommand, VertebraVariantOptionsOutOfRangeAreOneLineNamingTheOption) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> bad = {
      {{"--kind", "vertebra", "--disc-height-mm", "10"}, "--disc-height-mm: 10 mm does not fit"},
      {{"--kind", "vertebra", "--disc-height-mm", "2"}, "--disc-height-mm must be 0 (none) or 4 .. 15 mm"},
      {{"--kind", "vertebra", "--marrow-fat-radius-mm", "nan"}, "--marrow-fat-radius-mm"},
      {{"--kind", "vertebra", "--marrow-fat-radius-mm", "7"}, "--marrow-fat-radius-mm must be 0 (none) or 1 .. 6 mm"},
      {{"--kind", "vertebra", "--vein-radius-mm", "-1"}, "--vein-radius-mm must be 0 (none) or 1 .. 3 mm"},
      {{"--disc-height-mm", "6"}, "--disc-height-mm applies to --kind vertebra only"}};
  for (const auto& [extra, message] : bad) {
    const fs::path out = scratch("bad-variant");
    std::vector<std::string> args{"phantom", "--out", out.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = runProgram(CEMENTSPH_EXECUTABLE, args);
    EXPECT_NE(r.exitCode, 0) << message;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out)) << message;
  }
}
