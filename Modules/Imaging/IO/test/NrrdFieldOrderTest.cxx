// NRRD headers whose fields come in an order the NRRD reader cannot take (session 6's hostile cases): "space
// directions" or "space origin" before the "space:" line. readVolume refuses such a file with one line naming the
// file and the field, before the reader sees it (it said only "cannot read (corrupt or truncated ...)"); the same
// fields in the order the format asks for read back the values and spacing this test wrote (the oracle).
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

// A 2 x 2 x 2 short NRRD with the given geometry lines (in that order), voxel values 0 .. 7.
std::string writeNrrd(const std::string& name, const std::vector<std::string>& geometry) {
  const fs::path dir = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "nrrd-field-order";
  fs::create_directories(dir);
  std::string text = "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\n";
  for (const std::string& line : geometry) text += line + "\n";
  text += "endian: little\nencoding: raw\n\n";
  for (short v = 0; v < 8; ++v) text.append(reinterpret_cast<const char*>(&v), sizeof v);
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::string errorOf(const std::string& path) {
  try {
    (void)cementsph::imaging::readVolume(path);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "accepted";
}

} // namespace

TEST(NrrdFieldOrder, SpaceDirectionsBeforeSpaceAreRefusedNamingTheField) {
  const std::string late = writeNrrd("late-space.nrrd", {"space directions: (0.5,0,0) (0,0.5,0) (0,0,2)",
                                                         "space: left-posterior-superior", "space origin: (0,0,0)"});
  const std::string e = errorOf(late);
  EXPECT_EQ(e.rfind(late + ": space directions comes before any 'space:'", 0), 0u) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  const std::string origin = writeNrrd("origin-first.nrrd", {"space origin: (0,0,0)", "space: left-posterior-superior",
                                                             "space directions: (0.5,0,0) (0,0.5,0) (0,0,2)"});
  EXPECT_EQ(errorOf(origin).rfind(origin + ": space origin comes before", 0), 0u) << errorOf(origin);
}

TEST(NrrdFieldOrder, TheSameFieldsInTheFormatsOrderRead) {
  const std::string good = writeNrrd("good.nrrd", {"space: left-posterior-superior",
                                                   "space directions: (0.5,0,0) (0,0.5,0) (0,0,2)", "space origin: (0,0,0)"});
  const auto image = cementsph::imaging::readVolume(good);
  EXPECT_DOUBLE_EQ(image->GetSpacing()[0], 0.5);
  EXPECT_DOUBLE_EQ(image->GetSpacing()[2], 2.0);
  EXPECT_FLOAT_EQ(image->GetPixel({{1, 1, 1}}), 7.0f); // x fastest: 1 + 2*1 + 4*1
}
