// `cementsph demo` end to end on the bundled phantom: a pipeline check, not a validation of the model, whose
// one model-independent number is the cement volume the plan put in. The phantom's post scan was made by the same model
// with the same plan (truth.json), so simulation and "experiment" differ only by CT noise, the known
// misalignment (registered away) and how each CT's cement is segmented: the surfaces should agree within
// about one voxel diagonal (0.83 mm at 0.47 x 0.47 x 0.5 mm) and overlap with Dice >= 0.8.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <sys/wait.h>

namespace fs = std::filesystem;

TEST(DemoCommand, PipelineCheckOnTheBundledPhantomRecoversItsVolumeAndAgrees) {
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "demo";
  fs::remove_all(out);
  const std::string cmd = std::string(CEMENTSPH_EXECUTABLE) + " demo --threads 2 --out " + out.string() + " > " +
                          (out.string() + ".log") + " 2>&1";
  fs::create_directories(out.parent_path());
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "see " << out.string() << ".log";
  for (const char* f : {"inject/metrics.json", "inject/simulated_ct.nrrd", "inject/particles.pvd",
                        "inject/tip_pressure.csv", "inject/tip_pressure.png", "inject/sequence.json",
                        "inject/xray/xray_frames.png", "compare/metrics.json", "compare/surfaces.png",
                        "compare/slices.png", "xray/xray_frames.png", "xray/projected_area.png", "xray/sequence.csv",
                        "tip_pressure.png", "metrics.json"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  std::ifstream in(out / "compare" / "metrics.json");
  const auto m = nlohmann::json::parse(in);
  EXPECT_LT(m.at("error_mm").get<double>(), 0.83);
  EXPECT_GE(m.at("dice").get<double>(), 0.8);
  // An oracle that is not the model's: the plan injects 1 ml (truth.json's command, --volume-ml 1) and the
  // cement fills whole pore voxels, so the cement segmented from the registered post-injection CT holds 1 ml;
  // within 5 % (threshold and partial-volume voxels at the surface: 0.4 mm of a 5.7 mm radius ball is ~20 %
  // of its volume in the surface layer, half of it counted on average).
  EXPECT_NEAR(m.at("cement_volume_ml").get<double>(), 1.0, 0.05);
  // Issue 5, Fig. 12: the simulation's last X-ray frame against the registered post-injection CT's, held to
  // the 3-D bound above, 0.8 (projection folds the depth away, so the masks usually overlap better: measured
  // 0.90, IoU 0.82).
  std::ifstream demoIn(out / "metrics.json");
  const auto demo = nlohmann::json::parse(demoIn);
  EXPECT_GE(demo.at("xray").at("final_frame_dice").get<double>(), 0.8);
  EXPECT_GT(demo.at("xray").at("final_frame_iou").get<double>(), 0.0);
  EXPECT_EQ(demo.at("compare").at("dice").get<double>(), m.at("dice").get<double>());
  // Every headline figure is its step's own, as that step's metrics.json holds it (the demo's report is written
  // from the steps' typed results, each step's file by the step itself).
  std::ifstream injectIn(out / "inject" / "metrics.json"), xrayIn(out / "xray" / "metrics.json");
  const auto injectMetrics = nlohmann::json::parse(injectIn), xrayMetrics = nlohmann::json::parse(xrayIn);
  for (const auto& [key, value] : demo.at("inject").items()) EXPECT_EQ(value, injectMetrics.at(key)) << key;
  for (const auto& [key, value] : demo.at("compare").items()) EXPECT_EQ(value, m.at(key)) << key;
  for (const char* key : {"final_time_s", "final_projected_area_mm2", "final_reference_projected_area_mm2"})
    EXPECT_EQ(demo.at("xray").at(key), xrayMetrics.at(key)) << key;
  EXPECT_EQ(demo.at("xray").at("final_frame_dice"), xrayMetrics.at("final_frame").at("dice"));
  EXPECT_EQ(demo.at("xray").at("final_frame_iou"), xrayMetrics.at("final_frame").at("iou"));
  EXPECT_EQ(demo.at("inject").size(), 6u);
  EXPECT_EQ(demo.at("compare").size(), 5u);
  EXPECT_EQ(demo.at("xray").size(), 5u);
  // The post scan is the model's own (cementsph phantom): the demo must not present the comparison as a validation.
  EXPECT_EQ(demo.at("post_scan_made_by").get<std::string>(), "the model itself (pipeline check, not a validation)");
  std::ifstream inj(out / "inject" / "metrics.json");
  const auto mi = nlohmann::json::parse(inj);
  // The default engine has no particles, so no particle counts (not zeros standing in for them).
  EXPECT_EQ(mi.at("pressure_model").get<std::string>(), "voxel-darcy");
  EXPECT_FALSE(mi.contains("escaped_particles"));
  // Issue 4: in the foam phantom the cement stays in pore space (< 1 % of particle centres in solid).
  // Measured 0.3 % at this 100 Pa.s plan (1.3 % at 400 Pa.s: see VALIDATION.md).
  EXPECT_LT(mi.at("fluid_in_solid_fraction").get<double>(), 0.01);
}

TEST(DemoCommand, VertebraReadsTheDicomSeriesAndReportsTheLeak) {
  // The vertebra phantom's plan reaches its basivertebral foramen (VertebraPhantomTest checks where).
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "demo-vertebra";
  fs::remove_all(out);
  fs::create_directories(out.parent_path());
  const std::string cmd = std::string(CEMENTSPH_EXECUTABLE) + " demo --vertebra --out " + out.string() + " > " +
                          (out.string() + ".log") + " 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "see " << out.string() << ".log";
  std::ifstream in(out / "metrics.json");
  const auto m = nlohmann::json::parse(in);
  EXPECT_EQ(m.at("bone_model"), "continuum");
  EXPECT_GT(m.at("leakage_volume_ml").get<double>(), 0.0);
  EXPECT_FALSE(m.at("leakage_sites").empty());
  EXPECT_NEAR(m.at("cement_volume_ml").get<double>(), 4.0, 0.04);
  // The report's figures are the injection's own (inject/metrics.json), but the whole demo's wall time.
  std::ifstream injectIn(out / "inject" / "metrics.json");
  const auto inject = nlohmann::json::parse(injectIn);
  for (const auto& [key, value] : m.items())
    if (key != "wall_time_s" && key != "provenance") {
      EXPECT_EQ(value, inject.at(key)) << key;
    }
  EXPECT_GE(m.at("wall_time_s").get<double>(), inject.at("wall_time_s").get<double>());
  EXPECT_EQ(m.size(), 14u); // 12 figures, the wall time, the provenance
  EXPECT_TRUE(fs::exists(out / "inject" / "injection_pressure.png"));
  EXPECT_TRUE(fs::exists(out / "inject" / "cement_slices.png"));  // the leak in red (CementSlices test: colours)
  EXPECT_TRUE(fs::exists(out / "inject" / "cement_labels.nrrd"));
  EXPECT_TRUE(fs::exists(out / "inject" / "cement_surface.png")); // the leak red (CementSurface test: where)
}

namespace {
nlohmann::json injectOnPhantom(double viscosityPaS, const std::string& pressureModel) {
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / ("trend-" + pressureModel + "-" + std::to_string(int(viscosityPaS)));
  fs::remove_all(out);
  fs::create_directories(out.parent_path());
  const fs::path data = CEMENTSPH_TEST_DATA_DIR;
  const std::string cmd = std::string(CEMENTSPH_EXECUTABLE) + " inject --ct " + (data / "foam-phantom" / "pre.nrrd").string() +
                          " --scene " + (data / "scenes" / "paper-1ml.json").string() +
                          " --tip-mm 22.325,21.855,21.75 --quiet --viscosity-pa-s " + std::to_string(viscosityPaS) +
                          " --set pressure_model=" + pressureModel +
                          " --out " + out.string() + " > " + out.string() + ".log 2>&1";
  const int status = std::system(cmd.c_str());
  if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0)) return nullptr;
  std::ifstream in(out / "metrics.json");
  return nlohmann::json::parse(in);
}
} // namespace

TEST(PhantomTrend, SpreadingFallsAndPressureRisesFrom50To400PaS) {
  // The paper's trend (Figs. 8-10) with the paper's weakly compressible model: more viscous cement spreads
  // less and needs more pressure. Same phantom, tip, rate (0.05 ml/s) and volume (1 ml). Measured:
  // 6.23 -> 4.95 mm, 3.9 -> 5.1 kPa. (A compressibility artefact: VALIDATION.md, the viscosity trend.)
  const nlohmann::json thin = injectOnPhantom(50.0, "equation-of-state"), thick = injectOnPhantom(400.0, "equation-of-state");
  ASSERT_FALSE(thin.is_null());
  ASSERT_FALSE(thick.is_null());
  EXPECT_LT(thick.at("mean_spreading_distance_mm").get<double>(), thin.at("mean_spreading_distance_mm").get<double>());
  EXPECT_GT(thick.at("max_tip_pressure_pa").get<double>(), thin.at("max_tip_pressure_pa").get<double>());
}

TEST(PhantomTrend, IncompressibleDarcyPressureIsEightTimesAndTheCementTheSameFrom50To400PaS) {
  // The default model (voxel-grid Darcy filling), same runs: a Newtonian creeping flow at a fixed rate has a
  // pressure proportional to the viscosity (8.00 within 2 %, the tolerance) and a shape that does
  // not depend on it (mean spreading within 0.05 mm).
  const nlohmann::json thin = injectOnPhantom(50.0, "voxel-darcy"), thick = injectOnPhantom(400.0, "voxel-darcy");
  ASSERT_FALSE(thin.is_null());
  ASSERT_FALSE(thick.is_null());
  for (const char* key : {"final_tip_pressure_pa", "max_tip_pressure_pa", "injection_pressure_pa"})
    EXPECT_NEAR(thick.at(key).get<double>() / thin.at(key).get<double>(), 8.0, 0.16) << key;
  EXPECT_NEAR(thick.at("mean_spreading_distance_mm").get<double>(), thin.at("mean_spreading_distance_mm").get<double>(),
              0.05);
}

TEST(ViscosityCommand, Eq13BothWays) {
  // model-notes 4: 11G, 9 cm, 0.05 ml/s, 100 Pa.s -> 0.56 MPa; the inverse gives the viscosity back.
  const fs::path log = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "viscosity.log";
  fs::create_directories(log.parent_path());
  auto run = [&](const std::string& args) {
    const int status = std::system((std::string(CEMENTSPH_EXECUTABLE) + " viscosity " + args + " > " + log.string() + " 2>&1").c_str());
    std::ifstream in(log);
    std::string key;
    double value = -1;
    in >> key >> value;
    return std::make_pair(WIFEXITED(status) ? WEXITSTATUS(status) : -1, value);
  };
  // The oracle, Eq. 13 written out here: dP = 128 mu L Q / (pi D^4), 11G regular wall D = 2.388 mm, L = 90 mm,
  // Q = 0.05 ml/s; the command prints 6 significant digits.
  const double pi = 3.14159265358979323846, D = 2.388e-3;
  const double expectedMPa = 128.0 * 100.0 * 0.09 * 0.05e-6 / (pi * D * D * D * D) * 1e-6;
  const auto drop = run("--viscosity-pa-s 100");
  ASSERT_EQ(drop.first, 0);
  EXPECT_NEAR(drop.second / expectedMPa, 1.0, 1e-5);
  const auto mu = run("--pressure-drop-mpa " + std::to_string(drop.second));
  ASSERT_EQ(mu.first, 0);
  EXPECT_NEAR(mu.second, 100.0, 0.05);
  EXPECT_NE(run("--viscosity-pa-s 100 --pressure-drop-mpa 1").first, 0); // both: a clear error
}

TEST(ViscosityCommand, PowerLawDropAsJsonAndConsistencyBack) {
  // Rabinowitsch-Mooney for a power law, written out: dp = 2 K L / R ((3n+1)/n Q / (pi R^3))^n; 13G (1.803 mm).
  const fs::path log = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "viscosity-power.json";
  fs::create_directories(log.parent_path());
  auto run = [&](const std::string& args) {
    const int status = std::system((std::string(CEMENTSPH_EXECUTABLE) + " viscosity --json " + args + " > " + log.string() + " 2>/dev/null").c_str());
    std::ifstream in(log);
    return std::make_pair(WIFEXITED(status) ? WEXITSTATUS(status) : -1, nlohmann::json::parse(in, nullptr, false));
  };
  const double K = 250, n = 0.5, L = 0.09, Q = 0.05e-6, R = 0.5 * 1.803e-3, pi = 3.14159265358979323846;
  const double expected = 2 * K * L / R * std::pow((3 * n + 1) / n * Q / (pi * R * R * R), n);
  const auto drop = run("--consistency-pa-s-n 250 --flow-index 0.5 --cannula-gauge 13G");
  ASSERT_EQ(drop.first, 0);
  EXPECT_NEAR(drop.second.at("pressure_drop_pa").get<double>() / expected, 1.0, 1e-9);
  EXPECT_EQ(drop.second.at("law"), "power-law");
  const auto back = run("--pressure-drop-mpa " + std::to_string(expected * 1e-6) + " --flow-index 0.5 --cannula-gauge 13G");
  ASSERT_EQ(back.first, 0);
  EXPECT_NEAR(back.second.at("consistency_pa_s_n").get<double>(), 250.0, 1e-3);
  EXPECT_NE(run("--consistency-pa-s-n 250").first, 0); // no flow index: a clear error
  // A thin wall by name: 10GTW is 10G-thin, the midpoint of Component Supply's 0.112-0.116 in (TubeFlow.h).
  const auto thin = run("--viscosity-pa-s 100 --cannula-gauge 10GTW");
  ASSERT_EQ(thin.first, 0);
  EXPECT_EQ(thin.second.at("cannula_gauge"), "10G-thin");
  EXPECT_NEAR(thin.second.at("cannula_inner_diameter_mm").get<double>(), 0.114 * 25.4, 1e-9);
  EXPECT_NE(run("--viscosity-pa-s 100 --cannula-gauge 11G-thin").first, 0); // no sourced thin-wall 11G
  EXPECT_NE(run("--viscosity-pa-s 100 --cannula-gauge 9G").first, 0);       // unknown
}
