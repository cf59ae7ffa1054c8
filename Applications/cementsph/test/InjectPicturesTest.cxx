// `cementsph inject` writes the pictures that fit an injection (issue 5): tip_pressure.png (paper Fig. 10)
// always, and with the scene key simulated_ct_snapshots the X-ray sequence of the snapshots in DIR/xray
// (Fig. 12: xray_frames.png, projected_area.png, sequence.csv). Run headless (DISPLAY unset).
// Regression (InjectPicturesRegression): the pictures against baselines (Testing/Data/Baselines/inject_*.png,
// made from this scene, which sets every model key itself so that a change of an engine default shows as a
// changed picture; regenerate after an intended change with
//   CEMENTSPH_UPDATE_BASELINES=1 env -u DISPLAY build/bin/InjectPicturesTest --gtest_filter='InjectPicturesRegression.*'
// and look at them). Oracle: the X-ray area of the first frame is 0 mm^2 exactly (no cement yet: the frame
// minus itself); what the pictures draw is checked against oracles elsewhere (Testing/Data/Baselines/README.md).
#include "ProgramRun.h"
#include "RenderingTestSupport.h"
#include "ScaffoldCT.h"

#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

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
  // Every model key set here: the baselines must not follow a change of the engine's defaults unnoticed.
  std::ofstream(p / "scene.json") << R"({"tip_mm": [13, 13, 13], "volume_ml": 0.1, "cannula_length_mm": 5,
    "preset": "default", "integrator": "overdamped", "drag_coefficient": 8.7, "sound_speed_m_per_s": 1.0,
    "fixed_particle_sums": "tabulated", "fixed_field_spacing_over_h": 0.25, "max_displacement_over_h": 0.25,
    "neighbour_skin_over_h": 0.2, "pressure_model": "equation-of-state"})";
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

TEST(InjectPicturesRegression, TipPressureAndTheXraySequenceOfTheSnapshots) {
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
  EXPECT_GT(std::stod(last[1]), 1.0); // 0.1 ml of cement seen from the side: some mm^2 (measured ~30)
  std::ifstream csv(dir / "out" / "xray" / "sequence.csv");
  std::string header, first;
  std::getline(csv, header);
  std::getline(csv, first);
  EXPECT_EQ(std::stod(first.substr(first.find(',') + 1)), 0.0) << first; // frame 0 against itself: no cement

  using cementsph::rendering::test::expectMatchesBaseline;
  // Tolerances as the Rendering suite's: plots 2e-4 (a few anti-aliased pixels), DRR frames 1e-3.
  expectMatchesBaseline(dir / "out" / "tip_pressure.png", "inject_tip_pressure.png", 2e-4);
  expectMatchesBaseline(dir / "out" / "xray" / "projected_area.png", "inject_projected_area.png", 2e-4);
  expectMatchesBaseline(dir / "out" / "xray" / "xray_frames.png", "inject_xray_frames.png", 1e-3);
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

// inject projects its X-ray frames as the run makes them (InjectionRunOptions::onCtFrame), not from the files it
// wrote. Oracle: `cementsph xray` on the same output folder, which reads every frame volume back from disk through
// sequence.json: the same DRR frame files and sequence.csv byte for byte, the same metrics but for the timings and
// the provenance (the command line).
TEST(InjectPictures, TheXraySequenceProjectedDuringTheRunIsTheOneOfItsFiles) {
  const fs::path dir = scratch("inject-xray-in-memory");
  auto r = run({"inject", "--ct", (dir / "ct.nrrd").string(), "--scene", (dir / "scene.json").string(), "--out",
                (dir / "out").string(), "--snapshot-interval-s", "0.5", "--quiet", "--set", "simulated_ct_snapshots=true"});
  ASSERT_EQ(r.exitCode, 0) << r.out << r.err;
  r = run({"xray", "--sequence", (dir / "out").string(), "--out", (dir / "from-files").string(), "--no-pictures"});
  ASSERT_EQ(r.exitCode, 0) << r.out << r.err;
  const fs::path inMemory = dir / "out" / "xray", fromFiles = dir / "from-files";
  auto text = [](const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  EXPECT_EQ(text(inMemory / "sequence.csv"), text(fromFiles / "sequence.csv"));
  std::size_t frames = 0;
  for (; fs::exists(fromFiles / ("sequence_drr_000" + std::to_string(frames) + ".nrrd")); ++frames) {
    const std::string name = "sequence_drr_000" + std::to_string(frames) + ".nrrd"; // one writer: the same bytes
    const std::string a = text(inMemory / name), b = text(fromFiles / name);
    EXPECT_GT(a.size(), 1000u) << name; // a float DRR (compressed), not an empty file
    EXPECT_TRUE(a == b) << name << " differs";
  }
  EXPECT_EQ(frames, 5u); // t = 0 and the 4 snapshots
  auto metrics = [&](const fs::path& p) {
    auto m = nlohmann::json::parse(text(p / "metrics.json"));
    for (const char* key : {"timing_s", "provenance", "pictures", "render_backend"}) m.erase(key);
    return m;
  };
  EXPECT_EQ(metrics(inMemory), metrics(fromFiles));
}
