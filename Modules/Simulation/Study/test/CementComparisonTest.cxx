// compareCement (CementComparison.h), the computation behind `cementsph compare`, on volumes whose answers
// are known by construction: a 10 mm cube of cement (+2000 HU) on a uniform 1 mm grid is 1.000 ml; the same
// cube shifted by 2 voxels along x overlaps it in 8 x 10 x 10 voxels, so Dice = 2 x 800 / 2000 = 0.8,
// Jaccard = 800 / 1200 = 2/3, and the centroids are 2 mm apart.
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/study/CementComparison.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using cementsph::imaging::ImageType;

// A 40^3 volume, 1 mm voxels, origin 0: 0 HU, plus 2000 HU in the cube [x0, x0 + 10) x [15, 25) x [15, 25).
ImageType::Pointer volumeWithCube(int x0) {
  auto image = ImageType::New();
  ImageType::RegionType region;
  region.SetSize({40, 40, 40});
  image->SetRegions(region);
  image->Allocate();
  image->FillBuffer(0.0f);
  if (x0 >= 0)
    for (int z = 15; z < 25; ++z)
      for (int y = 15; y < 25; ++y)
        for (int x = x0; x < x0 + 10; ++x) image->SetPixel({x, y, z}, 2000.0f);
  return image;
}

class CementComparisonTest : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("cement_comparison_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    cementsph::imaging::writeVolume(volumeWithCube(-1), (dir_ / "pre.nrrd").string());
    cementsph::imaging::writeVolume(volumeWithCube(15), (dir_ / "post.nrrd").string());
    cementsph::imaging::writeVolume(volumeWithCube(17), (dir_ / "simulated.nrrd").string());
    request_.pre = (dir_ / "pre.nrrd").string();
    request_.post = (dir_ / "post.nrrd").string();
    request_.injectionMm = {20.0, 20.0, 20.0};
    request_.registration = false; // the scans are aligned by construction
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  cementsph::study::CementComparisonRequest request_;
};

TEST_F(CementComparisonTest, TheCubesVolumeOverlapAndCentroidOffsetAreTheConstructedOnes) {
  request_.simulated = (dir_ / "simulated.nrrd").string();
  const auto c = cementsph::study::compareCement(request_);
  EXPECT_EQ(c.ct.segmentation.voxels, 1000u);
  EXPECT_NEAR(c.ct.segmentation.volumeMl, 1.0, 1e-9);
  ASSERT_TRUE(c.sim.has_value());
  EXPECT_NEAR(c.sim->segmentation.volumeMl, 1.0, 1e-9);
  ASSERT_TRUE(c.overlap.has_value());
  EXPECT_NEAR(c.overlap->dice, 0.8, 1e-12);
  EXPECT_NEAR(c.overlap->jaccard, 2.0 / 3.0, 1e-12);
  ASSERT_TRUE(c.centroidOffsetMm.has_value());
  EXPECT_NEAR(*c.centroidOffsetMm, 2.0, 1e-9);
  EXPECT_NEAR(c.metrics.at("dice").get<double>(), 0.8, 1e-12);
  EXPECT_TRUE(c.warnings.empty());
}

TEST_F(CementComparisonTest, NothingIsWrittenUntilAskedAndThenEveryFile) {
  const auto out = dir_ / "out";
  auto c = cementsph::study::compareCement(request_);
  EXPECT_FALSE(fs::exists(out));
  cementsph::study::writeCementComparison(c, out);
  for (const char* name : {"registered_post.nrrd", "cement_ct_mask.nrrd", "cement_ct_surface.vtp", "metrics.json"})
    EXPECT_TRUE(fs::exists(out / name)) << name;
  EXPECT_FALSE(fs::exists(out / "pre_to_post.tfm")); // no registration, no transform
}

TEST_F(CementComparisonTest, APostScanWithoutCementIsRefusedNamingPost) {
  request_.post = request_.pre;
  try {
    (void)cementsph::study::compareCement(request_);
    FAIL() << "no cement was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--post " + request_.pre + ": no cement found", 0), 0u) << e.what();
  }
}

} // namespace
