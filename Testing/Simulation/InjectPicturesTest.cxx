// `cementsph inject` writes the pictures that fit an injection (issue 5): tip_pressure.png (paper Fig. 10)
// always, and with the scene key simulated_ct_snapshots the X-ray sequence of the snapshots in DIR/xray
// (Fig. 12: xray_frames.png, projected_area.png, sequence.csv). Run headless (DISPLAY unset).
// Oracle for the X-ray numbers: the sequence read through the folder's sequence.json ends with the same
// projected area as `cementsph xray` on the explicit pair (simulated_ct_start.nrrd, simulated_ct.nrrd)
// with the same tip: the last frame is the final simulated CT (exact equality of the areas).
#include "ProgramRun.h"
#include "ScaffoldCT.h"

#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

cementsph::testing::ProgramRun run(const std::vector<std::string>& args) {
  setenv("OMP_NUM_THREADS", "1", 1);
  unsetenv("DISPLAY"); // the headless case: the program starts its own Xvfb for the plots
  return cementsph::testing::runProgram(CEMENTSPH_EXECUTABLE, args);
}

fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  cementsph::imaging::writeVolume(cementsph::scene::testing::scaffold(), (p / "ct.nrrd").string());
  std::ofstream(p / "scene.json") << R"({"tip_mm": [13, 13, 13], "volume_ml": 0.1, "cannula_length_mm": 5})";
  return p;
}

std::vector<std::string> lastCsvRow(const fs::path& csv, std::size_t* rows) {
  std::ifstream in(csv);
  std::string line, last;
  *rows = 0;
  while (std::getline(in, line))
    if (!line.empty()) last = line, ++*rows;
  std::vector<std::string> fields;
  std::stringstream ss(last);
  while (std::getline(ss, line, ',')) fields.push_back(line);
  return fields;
}

} // namespace

TEST(InjectPictures, TipPressureAndTheXraySequenceOfTheSnapshots) {
  const fs::path dir = scratch("inject-pictures");
  const auto r = run({"inject", "--ct", (dir / "ct.nrrd").string(), "--scene", (dir / "scene.json").string(), "--out",
                      (dir / "out").string(), "--snapshot-interval-s", "0.5", "--quiet", "--set",
                      "simulated_ct_snapshots=true"});
  ASSERT_EQ(r.exitCode, 0) << r.out << r.err;
  for (const char* f : {"tip_pressure.png", "sequence.json", "xray/xray_frames.png", "xray/projected_area.png",
                        "xray/sequence.csv", "xray/metrics.json", "xray/sequence_drr_0004.nrrd"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  std::size_t rows = 0;
  const auto last = lastCsvRow(dir / "out" / "xray" / "sequence.csv", &rows);
  EXPECT_EQ(rows, 1u + 5u); // header, t = 0 and the 4 snapshots
  ASSERT_GE(last.size(), 2u);
  const double area = std::stod(last[1]);
  EXPECT_GT(area, 1.0); // 0.1 ml of cement seen from the side: some mm^2 (measured ~30)

  // The same last frame through an explicit list and the tip as the injection point.
  const auto list = run({"xray", "--sequence",
                         (dir / "out" / "simulated_ct_start.nrrd").string() + "," + (dir / "out" / "simulated_ct.nrrd").string(),
                         "--injection-point-mm", "13,13,13", "--no-pictures", "--out", (dir / "pair").string()});
  ASSERT_EQ(list.exitCode, 0) << list.err;
  const auto pair = lastCsvRow(dir / "pair" / "sequence.csv", &rows);
  EXPECT_EQ(rows, 3u);
  EXPECT_EQ(pair.at(1), last[1]); // identical text: identical area
}

TEST(InjectPictures, NoPicturesWritesNone) {
  const fs::path dir = scratch("inject-no-pictures");
  const auto r = run({"inject", "--ct", (dir / "ct.nrrd").string(), "--scene", (dir / "scene.json").string(), "--out",
                      (dir / "out").string(), "--quiet", "--no-pictures", "--set", "simulated_ct_snapshots=true"});
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "out" / "sequence.json"));
  EXPECT_FALSE(fs::exists(dir / "out" / "tip_pressure.png"));
  EXPECT_FALSE(fs::exists(dir / "out" / "xray"));
}
