// StagedFolder (the transactional output folder): nothing appears at the target until publish(); without
// publish the staging folder and the parents it created are gone; publish replaces same-named files, removes
// an earlier run's numbered files, and refuses (moving nothing) when a folder is in the way of a file.
#include "cementsph/imaging/StagedFolder.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using cementsph::imaging::StagedFolder;

class StagedFolderTest : public ::testing::Test {
protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("staged_folder_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  static std::string read(const fs::path& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  fs::path root_;
};

TEST_F(StagedFolderTest, WithoutPublishNothingIsLeftNotEvenTheParentsItMade) {
  const fs::path target = root_ / "new" / "deeper" / "out";
  {
    StagedFolder staged(target);
    std::ofstream(staged.path() / "a.txt") << "a";
    EXPECT_FALSE(fs::exists(target));
  }
  EXPECT_FALSE(fs::exists(root_ / "new"));
  EXPECT_TRUE(fs::is_empty(root_));
}

TEST_F(StagedFolderTest, PublishCreatesTheTargetWithTheFiles) {
  const fs::path target = root_ / "out";
  {
    StagedFolder staged(target);
    std::ofstream(staged.path() / "a.txt") << "a";
    staged.publish();
  }
  EXPECT_EQ(read(target / "a.txt"), "a");
  EXPECT_EQ(std::distance(fs::directory_iterator(root_), fs::directory_iterator()), 1); // no staging left
}

TEST_F(StagedFolderTest, PublishReplacesFilesAndRemovesAnEarlierRunsNumberedOnes) {
  const fs::path target = root_ / "out";
  fs::create_directories(target);
  for (const char* name : {"frame_0000.png", "frame_0001.png", "frame_0002.png", "keep.txt", "a.txt"})
    std::ofstream(target / name) << "old";
  {
    StagedFolder staged(target);
    std::ofstream(staged.path() / "frame_0000.png") << "new";
    std::ofstream(staged.path() / "a.txt") << "new";
    staged.publish({"frame_####.png"});
  }
  EXPECT_EQ(read(target / "frame_0000.png"), "new");
  EXPECT_FALSE(fs::exists(target / "frame_0001.png"));
  EXPECT_FALSE(fs::exists(target / "frame_0002.png"));
  EXPECT_EQ(read(target / "a.txt"), "new");
  EXPECT_EQ(read(target / "keep.txt"), "old"); // not ours: untouched
}

TEST_F(StagedFolderTest, AFolderInTheWayOfAFileMovesNothing) {
  const fs::path target = root_ / "out";
  fs::create_directories(target / "b.txt");
  std::ofstream(target / "a.txt") << "old";
  {
    StagedFolder staged(target);
    std::ofstream(staged.path() / "a.txt") << "new";
    std::ofstream(staged.path() / "b.txt") << "new";
    EXPECT_THROW(staged.publish(), std::runtime_error);
  }
  EXPECT_EQ(read(target / "a.txt"), "old");
  EXPECT_TRUE(fs::is_directory(target / "b.txt"));
  EXPECT_EQ(std::distance(fs::directory_iterator(root_), fs::directory_iterator()), 1); // no staging left
}

} // namespace
