// The scene key simulated_ct_snapshots (issue 5, X-ray sequences): the inject runner writes the simulated CT
// at t = 0 and at every particle snapshot, lists them in sequence.json, and the last one is the final
// simulated_ct.nrrd. Oracles: the t = 0 frame is the input CT's ROI voxel for voxel (no fluid yet); the last
// frame equals simulated_ct.nrrd exactly (the same state); frame times are the particle snapshots' times.
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/InjectionRunner.h"
#include "ScaffoldCT.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>

using namespace cementsph;
using namespace cementsph::scene;
namespace fs = std::filesystem;

namespace {

const int kOneThread = [] {
  omp_set_num_threads(1);
  return 1;
}();

// Largest absolute voxel difference of two volumes on one grid.
double maxDifference(const imaging::ImageType* a, const imaging::ImageType* b) {
  EXPECT_TRUE(imaging::geometryOf(a).sameGrid(imaging::geometryOf(b)));
  const std::size_t n = a->GetLargestPossibleRegion().GetNumberOfPixels();
  EXPECT_EQ(n, b->GetLargestPossibleRegion().GetNumberOfPixels());
  double worst = 0;
  for (std::size_t i = 0; i < n; ++i)
    worst = std::max(worst, double(std::abs(a->GetBufferPointer()[i] - b->GetBufferPointer()[i])));
  return worst;
}

InjectionRunResult runScaffold(const fs::path& out, bool snapshots) {
  fs::remove_all(out);
  const SceneConfig scene = sceneFromJson({{"tip_mm", {13, 13, 13}},
                                           {"volume_ml", 0.1},
                                           {"snapshot_interval_s", 0.5},
                                           {"cannula_length_mm", 5},
                                           {"simulated_ct_snapshots", snapshots}});
  InjectionRunOptions o;
  o.outDir = out.string();
  return runInjection(cementsph::scene::testing::scaffold(), scene, o);
}

} // namespace

TEST(SimulatedCtSnapshots, SceneKeyIsABoolOffByDefault) {
  EXPECT_FALSE(scenePreset("paper").simulatedCtSnapshots);
  const SceneConfig on = sceneFromJson({{"tip_mm", {1, 2, 3}}, {"simulated_ct_snapshots", true}});
  EXPECT_TRUE(on.simulatedCtSnapshots);
  EXPECT_TRUE(toJson(on).at("simulated_ct_snapshots").get<bool>());
  EXPECT_TRUE(sceneFromJson(toJson(on)).simulatedCtSnapshots); // round trip
  try {
    sceneFromJson({{"tip_mm", {1, 2, 3}}}, {"simulated_ct_snapshots=1"});
    FAIL() << "a number was accepted for a bool";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'simulated_ct_snapshots' must be true or false"), std::string::npos)
        << e.what();
  }
}

TEST(SimulatedCtSnapshots, FramesExistMatchTheSnapshotsAndEndAtTheFinalCT) {
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "ct-snapshots";
  const InjectionRunResult r = runScaffold(out, true);
  // 0.1 ml at 0.05 ml/s: 2 s, snapshots at 0.5, 1, 1.5 s and the end: 4, plus the t = 0 frame.
  ASSERT_EQ(r.metrics.at("snapshots").get<int>(), 4);
  EXPECT_EQ(r.metrics.at("simulated_ct_snapshots").get<int>(), 5);
  const double cost = r.metrics.at("simulated_ct_snapshots_wall_s").get<double>();
  EXPECT_TRUE(cost > 0 && cost < r.metrics.at("wall_time_s").get<double>() + 1.0) << cost;

  std::ifstream in(out / "sequence.json");
  ASSERT_TRUE(in) << "no sequence.json";
  const nlohmann::json seq = nlohmann::json::parse(in);
  const auto& frames = seq.at("frames");
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(frames[0].at("simulated_ct").get<std::string>(), "simulated_ct_start.nrrd");
  EXPECT_DOUBLE_EQ(frames[0].at("time_s").get<double>(), 0.0);
  EXPECT_TRUE(frames[0].at("particles").is_null());

  // The particle series' times, read from particles.pvd, are the frames' times.
  std::ifstream pvd(out / "particles.pvd");
  const std::string text((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  const std::regex entry("timestep=\"([^\"]+)\" part=\"0\" file=\"([^\"]+)\"");
  std::size_t k = 1;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it, ++k) {
    ASSERT_LT(k, frames.size());
    EXPECT_EQ(frames[k].at("particles").get<std::string>(), (*it)[2].str());
    EXPECT_NEAR(frames[k].at("time_s").get<double>(), std::stod((*it)[1].str()), 1e-8);
    char expected[64];
    std::snprintf(expected, sizeof expected, "simulated_ct_%04zu.nrrd", k - 1);
    EXPECT_EQ(frames[k].at("simulated_ct").get<std::string>(), expected);
    EXPECT_TRUE(fs::exists(out / expected)) << expected;
    if (k > 1) {
      EXPECT_GT(frames[k].at("time_s").get<double>(), frames[k - 1].at("time_s").get<double>());
    }
  }
  EXPECT_EQ(k, frames.size());
  EXPECT_NEAR(frames.back().at("time_s").get<double>(), r.metrics.at("simulated_time_s").get<double>(), 1e-12);

  // The last frame is the final simulated CT, voxel for voxel.
  const auto last = imaging::readVolume((out / frames.back().at("simulated_ct").get<std::string>()).string());
  const auto final = imaging::readVolume((out / "simulated_ct.nrrd").string());
  EXPECT_EQ(maxDifference(last, final), 0.0);

  // The t = 0 frame is the scaffold's ROI unchanged (1000 HU rods, -100 HU pores), and the cement makes
  // later frames brighter: the sum over the ROI rises from frame to frame.
  const auto start = imaging::readVolume((out / "simulated_ct_start.nrrd").string());
  const auto ct = cementsph::scene::testing::scaffold();
  double worst = 0;
  const auto roi = nlohmann::json(r.metrics.at("roi_start_index"));
  const auto size = start->GetLargestPossibleRegion().GetSize();
  for (long kk = 0; kk < long(size[2]); ++kk)
    for (long j = 0; j < long(size[1]); ++j)
      for (long i = 0; i < long(size[0]); ++i) {
        const float a = start->GetPixel({{i, j, kk}});
        const float b = ct->GetPixel({{i + roi[0].get<long>(), j + roi[1].get<long>(), kk + roi[2].get<long>()}});
        worst = std::max(worst, double(std::abs(a - b)));
      }
  EXPECT_EQ(worst, 0.0);
  double previous = -1e300;
  for (const auto& f : frames) {
    const auto v = imaging::readVolume((out / f.at("simulated_ct").get<std::string>()).string());
    double sum = 0;
    for (std::size_t i = 0; i < v->GetLargestPossibleRegion().GetNumberOfPixels(); ++i) sum += v->GetBufferPointer()[i];
    EXPECT_GT(sum, previous) << f.dump();
    previous = sum;
  }
}

TEST(SimulatedCtSnapshots, OffWritesNoFrames) {
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "ct-snapshots-off";
  const InjectionRunResult r = runScaffold(out, false);
  EXPECT_FALSE(r.metrics.contains("simulated_ct_snapshots"));
  EXPECT_FALSE(fs::exists(out / "sequence.json"));
  EXPECT_FALSE(fs::exists(out / "simulated_ct_start.nrrd"));
  EXPECT_FALSE(fs::exists(out / "simulated_ct_0000.nrrd"));
  EXPECT_TRUE(fs::exists(out / "simulated_ct.nrrd"));
}
