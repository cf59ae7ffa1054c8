// `cementsph inject` as a user meets it: a real run on a scaffold CT written as NRRD (files, metrics, the
// command-line override), and bad input (one line on stderr, exit 1, no output folder).
#include "ProgramRun.h"
#include "ScaffoldCT.h"

#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <cstdlib>
#include <fstream>

namespace fs = std::filesystem;

namespace {
struct Result {
  int status;
  std::string output; // stdout and stderr together
};

Result run(const std::string& args) {
  setenv("OMP_NUM_THREADS", "1", 1); // the child inherits it: one thread on shared cores
  const cementsph::testing::ProgramRun r = cementsph::testing::runProgram(CEMENTSPH_EXECUTABLE, args);
  return {r.exitCode, r.out + r.err};
}
fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}
fs::path writeCase(const fs::path& dir, const std::string& sceneJson) {
  cementsph::imaging::writeVolume(cementsph::scene::testing::scaffold(), (dir / "ct.nrrd").string());
  std::ofstream(dir / "scene.json") << sceneJson;
  return dir;
}
} // namespace

TEST(InjectCommand, RunsAndWritesTheResults) {
  const fs::path dir = writeCase(scratch("inject-cli"), R"({"tip_mm": [13, 13, 13], "volume_ml": 5, "cannula_length_mm": 5})");
  const Result r = run("inject --ct " + (dir / "ct.nrrd").string() + " --scene " + (dir / "scene.json").string() +
                       " --out " + (dir / "out").string() + " --volume-ml 0.1 --snapshot-interval-s 0.5");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("injected"), std::string::npos) << r.output;
  for (const char* f : {"metrics.json", "tip_pressure.csv", "particles.pvd", "simulated_ct.nrrd", "scene.json"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  std::ifstream in(dir / "out" / "metrics.json");
  const nlohmann::json m = nlohmann::json::parse(in);
  // The first snapshot: as growth with voxel-darcy (its default snapshot_arrays, a .pvtp), else whole.
  const bool growth = m["pressure_model"] == "voxel-darcy";
  EXPECT_TRUE(fs::exists(dir / "out" / (growth ? "particles_0000.pvtp" : "particles_0000.vtp"))) << m["pressure_model"];
  const double d3 = std::pow(1.14e-3, 3) * 1e6;
  EXPECT_GT(m["volume_injected_ml"].get<double>(), 0.1 - d3); // the override won over the file's 5 ml
  EXPECT_LE(m["volume_injected_ml"].get<double>(), 0.1);
  EXPECT_EQ(m["snapshots"].get<int>(), 4); // 0.5, 1, 1.5 s and the end (2 s)
  for (const auto& [key, value] : m.items()) {
    if (value.is_number()) {
      EXPECT_TRUE(std::isfinite(value.get<double>())) << key;
    }
  }
  // No temporary files left behind.
  for (const auto& e : fs::directory_iterator(dir / "out"))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

TEST(InjectCommand, BadSceneIsOneLineAndNoOutput) {
  const fs::path dir = writeCase(scratch("inject-bad"), R"({"tip_mm": [13, 13, 13], "volume_ml": 0.1, "flow_rate": 1})");
  const Result r = run("inject --ct " + (dir / "ct.nrrd").string() + " --scene " + (dir / "scene.json").string() +
                       " --out " + (dir / "out").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("unknown key 'flow_rate'"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// A value the scene refuses names what the user typed: the option (--flow-rate-ml-per-s, with the number as
// typed), or, through --set, the scene key; never the other one. 1e-9 ml/s takes 1e8 s for 0.1 ml, over the
// scene's one-day limit, yet is positive and finite, so it passes the option's own checks and reaches the scene's.
TEST(InjectCommand, ASceneLimitNamesTheOptionOrTheSetKeyTheUserTyped) {
  const fs::path dir = writeCase(scratch("inject-option-blame"), R"({"tip_mm": [13, 13, 13], "volume_ml": 0.1})");
  const std::string common = "inject --ct " + (dir / "ct.nrrd").string() + " --scene " + (dir / "scene.json").string() +
                             " --out " + (dir / "out").string();
  const Result option = run(common + " --flow-rate-ml-per-s 1e-9");
  EXPECT_EQ(option.status, 1);
  EXPECT_NE(option.output.find("--flow-rate-ml-per-s 1.0000000000000001e-09 (command line): scene: key "
                               "'flow_rate_ml_per_s' is too small"),
            std::string::npos)
      << option.output;
  EXPECT_EQ(option.output.find("override"), std::string::npos) << option.output;
  EXPECT_EQ(std::count(option.output.begin(), option.output.end(), '\n'), 1) << option.output;

  const Result set = run(common + " --set flow_rate_ml_per_s=1e-9");
  EXPECT_EQ(set.status, 1);
  EXPECT_NE(set.output.find("override flow_rate_ml_per_s=1e-9 (command line): scene: key 'flow_rate_ml_per_s' is too small"),
            std::string::npos)
      << set.output;
  EXPECT_EQ(set.output.find("--flow-rate-ml-per-s"), std::string::npos) << set.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(InjectCommand, TipInSolidIsOneLineAndNoOutput) {
  const fs::path dir = writeCase(scratch("inject-solid"), R"({"tip_mm": [0.5, 0.5, 13], "volume_ml": 0.1})");
  const Result r = run("inject --ct " + (dir / "ct.nrrd").string() + " --scene " + (dir / "scene.json").string() +
                       " --out " + (dir / "out").string() + " --set viscosity_pa_s=-3");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("'viscosity_pa_s' must be > 0"), std::string::npos) << r.output;
  const Result s = run("inject --ct " + (dir / "ct.nrrd").string() + " --scene " + (dir / "scene.json").string() +
                       " --out " + (dir / "out").string());
  EXPECT_EQ(s.status, 1);
  EXPECT_NE(s.output.find("lies in solid"), std::string::npos) << s.output;
  EXPECT_EQ(std::count(s.output.begin(), s.output.end(), '\n'), 1) << s.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(InjectCommand, ACementWithNowhereToGoIsAFailedRunExitTwo) {
  // A closed box: 18^3 pore voxels of 1 mm (5.832 ml) inside a solid shell, the tip at its centre. The pore
  // check before the run passes for 5.8 ml, but the cannula's shaft (11G, 0.33 mm wall: the voxels within
  // 1.524 mm of its axis behind the tip, 5 per slice over 9 slices) takes 45 of them: 5.787 ml is left.
  const fs::path dir = scratch("inject-full");
  auto img = cementsph::imaging::ImageType::New();
  cementsph::imaging::ImageType::RegionType region;
  cementsph::imaging::ImageType::SizeType size;
  size.Fill(20);
  region.SetSize(size);
  img->SetRegions(region);
  img->SetSpacing(1.0);
  img->Allocate();
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) {
        const bool shell = i == 0 || j == 0 || k == 0 || i == 19 || j == 19 || k == 19;
        img->SetPixel({{i, j, k}}, shell ? 1000.f : -100.f);
      }
  cementsph::imaging::writeVolume(img, (dir / "ct.nrrd").string());
  // The voxel-grid engine, as this test was written for: since fc52d15 "auto" picks particle-darcy for a
  // pore this open (the whole box), and particles filling 5.8 ml ran for minutes here (over the test's budget).
  std::ofstream(dir / "scene.json")
      << R"({"tip_mm": [10, 10, 10], "volume_ml": 5.8, "flow_rate_ml_per_s": 0.5, "pressure_model": "voxel-darcy"})";
  const Result r = run("inject --quiet --no-pictures --ct " + (dir / "ct.nrrd").string() + " --scene " +
                       (dir / "scene.json").string() + " --out " + (dir / "out").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("full"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "metrics.json"));
  for (const char* f : {"particles_0000.vtp", "particles_0000.pvtp", "particles_piece_0000.vtp"})
    EXPECT_FALSE(fs::exists(dir / "out" / f)) << f; // the failed run's snapshots went with it
}
