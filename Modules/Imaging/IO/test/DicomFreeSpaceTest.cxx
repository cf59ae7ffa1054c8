// writeDicomSeries' free-space check (issue 21 item 5): with less room than the series needs, the writer
// refuses in one line naming the folder and the sizes, and leaves nothing behind (no folder, no staging
// sibling). The room is injected (setFreeSpaceQuery) instead of filling a disk; the sizes the line names are
// the writer's documented estimate (slice pixels x 2 bytes + 4096 header bytes, plus 10 %), computed here.
#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace fs = std::filesystem;
using namespace cementsph::imaging;

namespace {

ImageType::Pointer smallVolume() {
  auto image = ImageType::New();
  ImageType::RegionType region;
  region.SetSize({{16, 12, 5}});
  image->SetRegions(region);
  image->Allocate();
  image->FillBuffer(100.0f);
  return image;
}

fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// The query in place for one test; statvfs again after.
struct FreeSpace {
  explicit FreeSpace(FreeSpaceQuery q) : previous(setFreeSpaceQuery(std::move(q))) {}
  ~FreeSpace() { setFreeSpaceQuery(previous); }
  FreeSpaceQuery previous;
};

} // namespace

TEST(DicomFreeSpace, TooLittleRoomIsOneLineAndNoOutput) {
  const fs::path dir = scratch("dicom-free-space");
  const fs::path target = dir / "series";
  std::string askedAbout;
  FreeSpace room([&](const std::string& folder) -> std::optional<std::uintmax_t> {
    askedAbout = folder;
    return 1000; // bytes
  });
  const auto image = smallVolume();
  try {
    writeDicomSeries(image, target.string());
    FAIL() << "a series that does not fit was written";
  } catch (const OutputError& e) {
    const std::string line = e.what();
    EXPECT_EQ(line.find('\n'), std::string::npos) << line;
    EXPECT_EQ(line.rfind(target.string() + ": not enough room for the DICOM series (", 0), 0u) << line;
    // needed = 5 slices x (16 x 12 x 2 + 4096) bytes x 1.1 = 24640 bytes = 0.0235 MB; free 1000 bytes.
    const std::uintmax_t slice = 16 * 12 * 2 + 4096, needed = slice * 5 + slice * 5 / 10;
    EXPECT_EQ(needed, 24640u);
    EXPECT_NE(line.find("(0.0235 MB needed, 0.000954 MB free)"), std::string::npos) << line;
  }
  // Asked about the folder it writes into (the staging sibling, on the target's filesystem).
  EXPECT_EQ(fs::path(askedAbout).parent_path(), dir) << askedAbout;
  // Nothing left: no series, no staging folder.
  EXPECT_FALSE(fs::exists(target));
  EXPECT_TRUE(fs::is_empty(dir)) << "left behind: " << fs::directory_iterator(dir)->path();
}

TEST(DicomFreeSpace, EnoughRoomOrAnUnknownRoomWrites) {
  const fs::path dir = scratch("dicom-free-space-ok");
  const auto image = smallVolume();
  {
    FreeSpace room([](const std::string&) -> std::optional<std::uintmax_t> { return 24640; }); // exactly enough
    writeDicomSeries(image, (dir / "exact").string());
  }
  {
    FreeSpace unknown([](const std::string&) -> std::optional<std::uintmax_t> { return std::nullopt; });
    writeDicomSeries(image, (dir / "unknown").string());
  }
  writeDicomSeries(image, (dir / "statvfs").string()); // the real query: this disk has 25 kB free
  for (const char* name : {"exact", "unknown", "statvfs"}) {
    std::size_t slices = 0;
    for (const auto& e : fs::directory_iterator(dir / name)) slices += e.path().extension() == ".dcm";
    EXPECT_EQ(slices, 5u) << name;
  }
}
