// Scene files: the paper preset's values, keys with units, overrides, and one clear error per bad input.
#include "cementsph/scene/SceneConfig.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <tuple>

using namespace cementsph::scene;
using nlohmann::json;

namespace {
// The message of the std::invalid_argument thrown by sceneFromJson(j, overrides), or "" if none.
std::string errorOf(const json& j, const std::vector<std::string>& overrides = {}) {
  try {
    sceneFromJson(j, overrides);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
json minimal() { return json{{"tip_mm", {1.0, 2.0, 3.0}}}; }
void expectError(const json& j, const std::string& key, const std::vector<std::string>& overrides = {}) {
  const std::string e = errorOf(j, overrides);
  EXPECT_NE(e.find("'" + key + "'"), std::string::npos) << "expected an error naming " << key << ", got: " << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}
} // namespace

TEST(SceneConfig, PaperPresetHoldsThePapersValues) {
  const SceneConfig s = sceneFromJson(minimal());
  EXPECT_EQ(s.scenePreset, "paper");
  EXPECT_EQ(s.modelPreset, "default");
  EXPECT_DOUBLE_EQ(s.particleRadiusMm, 0.57);
  EXPECT_DOUBLE_EQ(s.spacingM(), 1.14e-3);
  EXPECT_DOUBLE_EQ(s.cannulaInnerDiameterMm, 2.388);
  EXPECT_DOUBLE_EQ(s.cannulaLengthMm, 90.0);
  EXPECT_TRUE(s.cannulaWall);
  EXPECT_DOUBLE_EQ(s.flowRateMlPerS, 0.05);
  EXPECT_DOUBLE_EQ(s.volumeMl, 5.0);
  EXPECT_DOUBLE_EQ(s.injectionDurationS(), 100.0);
  EXPECT_DOUBLE_EQ(s.viscositySchedule().at(50.0), 100.0);
  EXPECT_DOUBLE_EQ(s.thresholdHu, 0.0);
  EXPECT_DOUBLE_EQ(s.roiSizeMm, 40.0);
  EXPECT_DOUBLE_EQ(s.snapshotIntervalS, 1.0);
  EXPECT_DOUBLE_EQ(s.solidMassFactor, 8.0);
  EXPECT_EQ(*s.tipMm, Eigen::Vector3d(1, 2, 3));
}

TEST(SceneConfig, EveryKeyIsReadAndOverridesWin) {
  const json j = {{"scene_preset", "paper"}, {"preset", "paper"}, {"particle_radius_mm", 0.5},
                  {"tip_mm", {1, 2, 3}}, {"direction", {1, 0, 0}}, {"cannula_inner_diameter_mm", 3.0},
                  {"cannula_length_mm", 20}, {"cannula_wall", false}, {"flow_rate_ml_per_s", 0.1},
                  {"volume_ml", 2}, {"viscosity_pa_s", 50}, {"viscosity_rate_pa_per_s", 25},
                  {"threshold_hu", 200}, {"roi_size_mm", 30}, {"snapshot_interval_s", 0.5},
                  {"drag_coefficient", 4.0}, {"sound_speed_m_per_s", 2.0}, {"solid_mass_factor", 3.0}, {"integrator", "overdamped"}};
  const SceneConfig s = sceneFromJson(j, {"volume_ml=0.2", "cannula_wall=true", "integrator=explicit"});
  EXPECT_EQ(s.modelPreset, "paper");
  EXPECT_DOUBLE_EQ(s.particleRadiusMm, 0.5);
  EXPECT_EQ(s.direction, Eigen::Vector3d(1, 0, 0));
  EXPECT_DOUBLE_EQ(s.cannulaInnerDiameterMm, 3.0);
  EXPECT_DOUBLE_EQ(s.cannulaLengthMm, 20.0);
  EXPECT_TRUE(s.cannulaWall);              // overridden
  EXPECT_DOUBLE_EQ(s.volumeMl, 0.2);       // overridden
  EXPECT_EQ(*s.integrator, "explicit");    // overridden, bare word
  EXPECT_DOUBLE_EQ(s.flowRateMlPerS, 0.1);
  EXPECT_DOUBLE_EQ(s.viscositySchedule().at(2.0), 100.0); // 50 + 25 * 2
  EXPECT_DOUBLE_EQ(s.thresholdHu, 200.0);
  EXPECT_DOUBLE_EQ(s.roiSizeMm, 30.0);
  EXPECT_DOUBLE_EQ(s.snapshotIntervalS, 0.5);
  EXPECT_DOUBLE_EQ(*s.dragCoefficient, 4.0);
  EXPECT_DOUBLE_EQ(s.solidMassFactor, 3.0);
  EXPECT_DOUBLE_EQ(*s.soundSpeedMPerS, 2.0);
  // Round trip through toJson.
  const SceneConfig r = sceneFromJson(toJson(s));
  EXPECT_EQ(toJson(r), toJson(s));
}

TEST(SceneConfig, ViscosityTable) {
  json j = minimal();
  j["viscosity_table"] = {{0, 50}, {10, 150}};
  const SceneConfig s = sceneFromJson(j);
  EXPECT_DOUBLE_EQ(s.viscositySchedule().at(5.0), 100.0);
  EXPECT_DOUBLE_EQ(s.viscositySchedule().at(20.0), 150.0);
}

TEST(SceneConfig, UnknownKeyIsNamed) {
  json j = minimal();
  j["volume_mL"] = 1;
  EXPECT_EQ(errorOf(j), "scene: unknown key 'volume_mL'");
  expectError(minimal(), "flow_rate", {"flow_rate=1"});
}

TEST(SceneConfig, MissingValuesAreNamed) {
  EXPECT_EQ(errorOf(json::object()), "scene: key 'tip_mm' is missing (the cannula tip [x, y, z] in mm)");
  json j = minimal();
  j["volume_ml"] = nullptr;
  expectError(j, "volume_ml");
  expectError(minimal(), "volume_ml", {"volume_ml="});
  expectError(minimal(), "volume_ml", {"volume_ml=\"lots\""}); // wrong type
  json t = minimal();
  t["tip_mm"] = {1, 2};
  expectError(t, "tip_mm");
}

TEST(SceneConfig, OutOfRangeValuesAreNamed) {
  for (const char* key : {"particle_radius_mm", "viscosity_pa_s", "viscosity_rate_pa_per_s", "flow_rate_ml_per_s",
                          "volume_ml", "cannula_inner_diameter_mm", "cannula_length_mm", "roi_size_mm",
                          "snapshot_interval_s", "solid_mass_factor", "drag_coefficient", "sound_speed_m_per_s"}) {
    for (double bad : {0.0, -1.0}) {
      json j = minimal();
      j[key] = bad;
      expectError(j, key);
    }
  }
  json d = minimal();
  d["direction"] = {0, 0, 0};
  expectError(d, "direction");
  json v = minimal();
  v["viscosity_table"] = {{0, 50}, {0, 60}};
  expectError(v, "viscosity_table");
  v["viscosity_table"] = {{0, 50}, {1, -60}};
  expectError(v, "viscosity_table");
  json p = minimal();
  p["preset"] = "fast";
  expectError(p, "preset");
  p = minimal();
  p["integrator"] = "leapfrog";
  expectError(p, "integrator");
  p = minimal();
  p["scene_preset"] = "vertebra";
  expectError(p, "scene_preset");
}

TEST(SceneConfig, FileErrorsNameThePath) {
  const auto dir = std::filesystem::temp_directory_path() / "cementsph-scene-test";
  std::filesystem::create_directories(dir);
  const auto path = (dir / "scene.json").string();
  {
    std::ofstream(path) << R"({"tip_mm": [0, 0, 0], "volume_ml": -2})";
  }
  try {
    loadSceneFile(path);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), path + ": scene: key 'volume_ml' must be > 0 (got -2)");
  }
  EXPECT_DOUBLE_EQ(loadSceneFile(path, {"volume_ml=0.3"}).volumeMl, 0.3);
  {
    std::ofstream(path) << "{ not json";
  }
  EXPECT_THROW(loadSceneFile(path), std::invalid_argument);
  EXPECT_THROW(loadSceneFile((dir / "missing.json").string()), std::invalid_argument);
}

TEST(SceneConfig, TheModelAndRheologyKeysAreReadAndCheckedNamingTheKey) {
  json j = minimal();
  j["viscosity_law"] = "carreau";
  j["zero_shear_viscosity_pa_s"] = 300.0;
  j["carreau_time_constant_s"] = 2.0;
  j["flow_index"] = 0.4;
  j["curing_table"] = {{0.0, 1.0}, {600.0, 5.0}};
  j["mixing_to_injection_s"] = 300.0;
  j["cannula_gauge"] = "13G";
  const SceneConfig s = sceneFromJson(j);
  EXPECT_EQ(s.viscosityLaw, "carreau");
  EXPECT_DOUBLE_EQ(s.rheology.zeroShearViscosityPaS, 300.0);
  EXPECT_DOUBLE_EQ(s.cannulaInnerDiameterMm, 1.803);    // the gauge table
  EXPECT_DOUBLE_EQ(s.curingFactor(0.0), 3.0);           // 300 s after mixing: halfway from 1 to 5
  EXPECT_DOUBLE_EQ(s.curingFactor(1000.0), 5.0);        // held past the table
  EXPECT_EQ(sceneFromJson(toJson(s)).cannulaInnerDiameterMm, 1.803); // round trip
  json thin = minimal();
  thin["cannula_gauge"] = "10GTW"; // thin wall: ID 0.112-0.116 in (Component Supply; TubeFlow.h), the midpoint
  const SceneConfig t = sceneFromJson(thin);
  EXPECT_NEAR(t.cannulaInnerDiameterMm, 0.114 * 25.4, 1e-12);
  EXPECT_EQ(*t.cannulaGauge, "10G-thin"); // canonical
  EXPECT_EQ(sceneFromJson(toJson(t)).cannulaInnerDiameterMm, t.cannulaInnerDiameterMm);
  for (const auto& [key, bad] : std::vector<std::pair<std::string, json>>{
           {"viscosity_law", "bingham"},
           {"pore_permeability_m2", 1e300},
           {"capillary_tension_n_per_m", -1.0},
           {"contact_angle_deg", 90.0}, // the cement would wet the bone: imbibition, not an entry pressure
           {"contact_angle_deg", -1.0},
           {"curing_table", json{{0.0, 1.0}, {0.0, 2.0}}},
           {"curing_table", json{{0.0, -1.0}}},
           {"mixing_to_injection_s", -5.0},
           {"cannula_gauge", "99G"},
           {"cannula_gauge", "11G-thin"}, // no sourced thin-wall 11G
           // Not a model's name in form (a well-formed unknown name is the driver's to refuse, listing the
           // registered models: InjectionModel.AnUnknownNameIsOneLineListingTheModels).
           {"pressure_model", "Magic model!"}}) {
    json k = minimal();
    k[key] = bad;
    expectError(k, key);
  }
}

TEST(SceneConfig, ABundledCementCuresExponentiallyFromTheLawsViscosityAndBadCuringKeysAreOneError) {
  // CMW 1 at 25 C (Nicholas et al. 2007): 75e3 Pa s at 8.7 min after mixing. The power law's K = 200 Pa s^n
  // holds at 120 s after mixing; the injection starts 240 s after mixing.
  json j = minimal();
  j["viscosity_law"] = "power-law";
  j["consistency_pa_s_n"] = 200.0;
  j["flow_index"] = 0.5;
  j["cement"] = "cmw1-25c";
  j["curing_reference_time_s"] = 120.0;
  j["mixing_to_injection_s"] = 240.0;
  const SceneConfig s = sceneFromJson(j);
  EXPECT_EQ(s.curing().kind(), "exponential");
  EXPECT_DOUBLE_EQ(s.referenceViscosityPaS(), 200.0); // the factor multiplies K
  const double tau = (522.0 - 120.0) / std::log(75e3 / 200.0);
  EXPECT_NEAR(s.curingFactor(0.0), std::exp(120.0 / tau), 1e-12 * std::exp(120.0 / tau));
  EXPECT_NEAR(s.curingFactor(60.0), std::exp(180.0 / tau), 1e-12 * std::exp(180.0 / tau));
  EXPECT_NEAR(200.0 * s.curingFactor(522.0 - 240.0), 75e3, 1e-9 * 75e3); // the source's cured viscosity
  EXPECT_DOUBLE_EQ(s.curingFactor(1000.0), 75e3 / 200.0);              // held
  const SceneConfig back = sceneFromJson(toJson(s));                  // round trip
  EXPECT_DOUBLE_EQ(back.curingFactor(60.0), s.curingFactor(60.0));
  // Explicit points win over the cement's; a Newtonian cement's reference is viscosity_pa_s.
  json e = minimal();
  e["curing_model"] = "exponential";
  e["curing_time_s"] = 600.0;
  e["cured_viscosity_pa_s"] = 1e4;
  e["viscosity_pa_s"] = 100.0;
  const SceneConfig x = sceneFromJson(e);
  EXPECT_NEAR(x.curingFactor(600.0), 100.0, 1e-9);
  EXPECT_NEAR(x.curingFactor(300.0), 10.0, 1e-9); // halfway: sqrt(100)
  for (const auto& [key, bad] : std::vector<std::pair<std::string, json>>{
           {"cement", "simplex-p"},
           {"curing_model", "magic"},
           {"curing_time_s", -1.0},           // before the reference time (0)
           {"cured_viscosity_pa_s", 50.0},     // below the law's 100 Pa s
           {"curing_reference_time_s", -3.0}}) {
    json k = e;
    k[key] = bad;
    expectError(k, key);
  }
  json noTime = minimal();
  noTime["curing_model"] = "exponential";
  noTime["cured_viscosity_pa_s"] = 1e4;
  expectError(noTime, "curing_time_s");
  json twoRises = e;
  twoRises["viscosity_rate_pa_per_s"] = 1.0;
  expectError(twoRises, "viscosity_rate_pa_per_s");
  json tableToo = e;
  tableToo["curing_table"] = json{{0.0, 1.0}, {10.0, 2.0}};
  expectError(tableToo, "curing_table");
  json tableNone = minimal();
  tableNone["curing_model"] = "table";
  expectError(tableNone, "curing_model");
}

// Issue 21: limits that follow from physics or the machine. The oracles are the limits' definitions: an
// injection of volume_ml at flow_rate_ml_per_s lasts volume/flow s and must be within a day (86400 s);
// it may write at most 10000 snapshots (duration / snapshot_interval_s); sound speed 1e-3..1500 m/s and
// drag coefficient 1e-6..1e6. Each is tested 1 % either side of its limit.
TEST(SceneConfig, LimitsFromPhysicsAndTheMachineNameTheKey) {
  const double volumeMl = 5.0, dayS = 86400.0;
  json j = minimal();
  j["volume_ml"] = volumeMl;
  j["flow_rate_ml_per_s"] = volumeMl / dayS * 0.99;
  expectError(j, "flow_rate_ml_per_s");
  j["flow_rate_ml_per_s"] = 1e-300;
  expectError(j, "flow_rate_ml_per_s");
  j["flow_rate_ml_per_s"] = volumeMl / dayS * 1.01;
  j["snapshot_interval_s"] = 1000.0;
  EXPECT_EQ(errorOf(j), "");

  json s = minimal();
  s["volume_ml"] = volumeMl;
  s["flow_rate_ml_per_s"] = 0.05; // 100 s of injection
  for (double interval : {100.0 / 10000 * 0.99, 1e-300, 4.9e-324}) {
    s["snapshot_interval_s"] = interval;
    expectError(s, "snapshot_interval_s");
  }
  s["snapshot_interval_s"] = 100.0 / 10000 * 1.01;
  EXPECT_EQ(errorOf(s), "");

  for (const auto& [key, bad, good] : {std::tuple{"sound_speed_m_per_s", 1500.0 * 1.01, 1500.0 * 0.99},
                                       std::tuple{"sound_speed_m_per_s", 1e-3 * 0.99, 1e-3 * 1.01},
                                       std::tuple{"drag_coefficient", 1e6 * 1.01, 1e6 * 0.99},
                                       std::tuple{"drag_coefficient", 1e-6 * 0.99, 1e-6 * 1.01}}) {
    json k = minimal();
    k[key] = bad;
    expectError(k, key);
    k[key] = good;
    EXPECT_EQ(errorOf(k), "") << key << " " << good;
  }
  // NaN and infinity cannot be written in JSON; from the command line they are refused naming the key.
  for (const char* key : {"sound_speed_m_per_s", "drag_coefficient", "snapshot_interval_s", "flow_rate_ml_per_s",
                          "fixed_field_spacing_over_h", "max_displacement_over_h", "particle_radius_mm"})
    for (const char* value : {"nan", "NaN", "inf", "-inf", "1e999"})
      expectError(minimal(), key, {std::string(key) + "=" + value});
}

// A value or key of a megabyte is echoed cut short: the message stays one line of bounded length.
TEST(SceneConfig, HugeValuesAreNotEchoedWhole) {
  const std::string huge(1 << 20, 'x');
  for (const char* key : {"preset", "integrator", "pressure_model", "viscosity_law", "bone_model", "cement"}) {
    json j = minimal();
    j[key] = huge;
    const std::string e = errorOf(j);
    EXPECT_NE(e.find(key), std::string::npos) << e.substr(0, 200);
    EXPECT_LT(e.size(), 300u) << key;
  }
  json k = minimal();
  k[huge] = 1;
  EXPECT_LT(errorOf(k).size(), 300u);
  EXPECT_LT(errorOf(minimal(), {huge}).size(), 300u);
  EXPECT_LT(errorOf(minimal(), {"preset=" + huge}).size(), 300u);
}

// A scene file is one JSON object and nothing else: NUL bytes (which a stream parser takes for the end of
// input) or text after the object are refused naming the file; trailing white space is fine.
TEST(SceneConfig, TrailingNulBytesOrGarbageAreRefused) {
  const auto dir = std::filesystem::temp_directory_path() / "cementsph-scene-trailing";
  std::filesystem::create_directories(dir);
  const auto path = (dir / "scene.json").string();
  const std::string object = R"({"tip_mm": [4, 5, 6]})";
  auto write = [&](const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; };
  write(object + "\n\t \n");
  EXPECT_DOUBLE_EQ(loadSceneFile(path).tipMm->z(), 6.0);
  for (const std::string& tail : {std::string("\0\0\0", 3), std::string("\0garbage", 8), std::string(" garbage"),
                                  std::string("{}"), std::string(" ,")}) {
    write(object + tail);
    try {
      loadSceneFile(path);
      ADD_FAILURE() << "accepted a scene followed by " << tail.size() << " bytes";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    }
  }
  write(std::string("\0", 1) + object);
  EXPECT_THROW(loadSceneFile(path), std::invalid_argument);
}

// The keys the user set are recorded (the scene file's and the command line's), not the preset's defaults; the
// driver warns of those the chosen engine does not read (SceneKeysTest).
TEST(SceneConfig, RecordsTheKeysTheUserSet) {
  const SceneConfig s = sceneFromJson({{"tip_mm", {1.0, 2.0, 3.0}}, {"volume_ml", 0.5}}, {"integrator=overdamped"});
  EXPECT_EQ(s.explicitKeys, (std::set<std::string>{"tip_mm", "volume_ml", "integrator"}));
  EXPECT_TRUE(scenePreset("paper").explicitKeys.empty());
}

// sceneKeyNames() is the parser's list: each name is taken as a key (a value of the wrong type is refused naming
// the key, never as an unknown key), and a name outside it is an unknown key.
TEST(SceneConfig, TheListOfKeyNamesIsTheParsers) {
  EXPECT_EQ(sceneKeyNames().size(), 59u); // the parser's branches, counted apart (the key == "..." tests)
  for (const std::string& key : sceneKeyNames()) {
    SceneConfig s;
    try {
      applySceneJson(s, json{{key, json::array({json::object()})}}); // no key takes [{}]
      ADD_FAILURE() << key << " took [{}]";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).find("unknown key"), std::string::npos) << key << ": " << e.what();
    }
  }
  SceneConfig s;
  EXPECT_THROW(applySceneJson(s, json{{"particle_radius", 0.5}}), std::invalid_argument);
}

// A command's typed settings (SceneSettings: inject's --tip-mm, --volume-ml, ...; plan's entry; demo's plan) are
// set in the scene's fields as given, over the file's keys and the --set list, before the scene is checked, and
// recorded as keys the user set. Oracle: the values the test sets, and the lines worked out by hand below (each
// the line the same value gave as a "key=value" override, which the test also runs).
TEST(SceneConfig, TypedSettingsLandInTheirFieldsBeforeTheCheckAndAreRecorded) {
  const auto dir = std::filesystem::temp_directory_path() / "cementsph-scene-settings-test";
  std::filesystem::create_directories(dir);
  const auto path = (dir / "scene.json").string();
  {
    // volume_ml -2 is refused by the check unless a setting replaces it first.
    std::ofstream(path) << R"({"tip_mm": [0, 0, 0], "volume_ml": -2, "viscosity_table": [[0, 50], [60, 200]]})";
  }
  SceneSettings g;
  g.set = {"volume_ml=9", "integrator=overdamped"};
  g.tipMm = {1.5, -2.25, 3.0};
  g.direction = {0.0, -1.0, 0.0};
  g.volumeMl = 0.25; // a typed field wins over a --set of the same key
  g.flowRateMlPerS = 0.02;
  g.viscosityPaS = 80.0; // a constant viscosity replaces the file's table, as the key does
  g.snapshotIntervalS = 0.5;
  g.simulatedCtSnapshots = true;
  g.modelPreset = "default";
  const SceneConfig s = loadSceneFile(path, g);
  EXPECT_EQ(*s.tipMm, Eigen::Vector3d(1.5, -2.25, 3.0));
  EXPECT_EQ(s.direction, Eigen::Vector3d(0.0, -1.0, 0.0));
  EXPECT_EQ(s.volumeMl, 0.25);
  EXPECT_EQ(s.flowRateMlPerS, 0.02);
  EXPECT_EQ(s.viscosityPaS, 80.0);
  EXPECT_TRUE(s.viscosityTable.empty());
  EXPECT_EQ(s.snapshotIntervalS, 0.5);
  EXPECT_TRUE(s.simulatedCtSnapshots);
  EXPECT_EQ(s.modelPreset, "default");
  EXPECT_EQ(s.integrator, std::optional<std::string>("overdamped")); // the --set list still applies
  EXPECT_EQ(s.explicitKeys, (std::set<std::string>{"tip_mm", "volume_ml", "viscosity_table", "integrator", "direction",
                                                   "flow_rate_ml_per_s", "viscosity_pa_s", "snapshot_interval_s",
                                                   "simulated_ct_snapshots", "preset"}));
  // With no settings the file's bad volume is what the check sees.
  EXPECT_THROW(loadSceneFile(path, SceneSettings()), std::invalid_argument);

  auto errorOfSettings = [&](const SceneSettings& settings) {
    try {
      (void)loadSceneFile(path, settings);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  auto errorOfOverride = [&](const std::string& assignment) {
    try {
      (void)loadSceneFile(path, std::vector<std::string>{"volume_ml=5", assignment});
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  SceneSettings slow;
  slow.volumeMl = 5.0;
  slow.flowRateMlPerS = std::ldexp(1.0, -20); // 9.5367431640625e-07 ml/s exactly: 5 ml take 61 days
  const std::string slowLine = errorOfSettings(slow);
  EXPECT_EQ(slowLine.rfind("override flow_rate_ml_per_s=9.5367431640625e-07 (command line): scene: key "
                           "'flow_rate_ml_per_s' is too small: ",
                           0),
            0u)
      << slowLine;
  EXPECT_EQ(slowLine, errorOfOverride("flow_rate_ml_per_s=9.5367431640625e-07"));

  SceneSettings notFinite;
  notFinite.volumeMl = 5.0;
  notFinite.tipMm = {std::nan(""), 0.0, 0.0};
  EXPECT_EQ(errorOfSettings(notFinite), "override tip_mm=[nan,0,0] (command line): scene: key 'tip_mm' must be finite");

  SceneSettings unknownPreset;
  unknownPreset.volumeMl = 5.0;
  unknownPreset.modelPreset = "fast";
  EXPECT_EQ(errorOfSettings(unknownPreset),
            "override preset=\"fast\" (command line): scene: key 'preset' must be \"default\" or \"paper\" (got \"fast\")");
  EXPECT_EQ(errorOfSettings(unknownPreset), errorOfOverride("preset=\"fast\""));

  // A key the settings did not set is the file's fault: the line names the file.
  SceneSettings tipOnly;
  tipOnly.tipMm = {1.0, 2.0, 3.0};
  EXPECT_EQ(errorOfSettings(tipOnly), path + ": scene: key 'volume_ml' must be > 0 (got -2)");
}

// A typed field given by a command-line option (SceneSettings::optionOfKey) is blamed on that option, as the user
// typed it (number, x,y,z, bare text); the same value through --set, or a typed field with no option (a plan's),
// names the scene key as key=value.
TEST(SceneConfig, ARefusedSettingNamesTheOptionThatGaveIt) {
  const auto dir = std::filesystem::temp_directory_path() / "cementsph-scene-option-blame-test";
  std::filesystem::create_directories(dir);
  const auto path = (dir / "scene.json").string();
  std::ofstream(path) << R"({"tip_mm": [0, 0, 0], "volume_ml": 5})";
  auto errorOf = [&](const SceneSettings& settings) {
    try {
      (void)loadSceneFile(path, settings);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  SceneSettings slow;
  slow.flowRateMlPerS = std::ldexp(1.0, -20); // 5 ml take 61 days: over the one-day limit
  slow.optionOfKey = {{"flow_rate_ml_per_s", "--flow-rate-ml-per-s"}};
  EXPECT_EQ(errorOf(slow).rfind("--flow-rate-ml-per-s 9.5367431640625e-07 (command line): scene: key "
                                "'flow_rate_ml_per_s' is too small: ",
                                0),
            0u)
      << errorOf(slow);
  slow.optionOfKey.clear();
  EXPECT_EQ(errorOf(slow).rfind("override flow_rate_ml_per_s=9.5367431640625e-07 (command line): ", 0), 0u)
      << errorOf(slow);

  SceneSettings tip;
  tip.tipMm = {std::nan(""), 0.0, 0.0};
  tip.optionOfKey = {{"tip_mm", "--tip-mm"}};
  EXPECT_EQ(errorOf(tip), "--tip-mm nan,0,0 (command line): scene: key 'tip_mm' must be finite");

  SceneSettings preset;
  preset.modelPreset = "fast";
  preset.optionOfKey = {{"preset", "--preset"}};
  EXPECT_EQ(errorOf(preset),
            "--preset fast (command line): scene: key 'preset' must be \"default\" or \"paper\" (got \"fast\")");

  // The option names only its own key: a --set of another key is still "override key=value".
  SceneSettings viaSet;
  viaSet.set = {"viscosity_pa_s=-1"};
  viaSet.optionOfKey = {{"flow_rate_ml_per_s", "--flow-rate-ml-per-s"}};
  EXPECT_EQ(errorOf(viaSet).rfind("override viscosity_pa_s=-1 (command line): scene: key 'viscosity_pa_s' must be > 0", 0),
            0u)
      << errorOf(viaSet);
}

// Physical limits on the cement (SceneConfig.cpp): a viscosity above 1e7 Pa.s (a setting PMMA dough is 1e4-1e5)
// and a volume below 1e-3 ml (one cubic millimetre) are refused naming the key; the limits themselves and the
// bundled cements' range pass. 1e308 Pa.s once reached the run and came back as a non-finite "marrow viscosity
// ratio" blamed on the flow rate.
TEST(SceneConfig, ViscosityAndVolumeOutsideTheirPhysicalRangeAreRefused) {
  for (double mu : {1e7 * 1.000001, 1e9, 1e308}) {
    json j = minimal();
    j["viscosity_pa_s"] = mu;
    expectError(j, "viscosity_pa_s");
  }
  json table = minimal();
  table["viscosity_table"] = json::array({json::array({0.0, 100.0}), json::array({60.0, 2e7})});
  expectError(table, "viscosity_table");
  for (double v : {1e-30, 0.000999}) {
    json j = minimal();
    j["volume_ml"] = v;
    expectError(j, "volume_ml");
  }
  for (double mu : {1e7, 3000.0, 10.0}) {
    json j = minimal();
    j["viscosity_pa_s"] = mu;
    EXPECT_EQ(errorOf(j), "") << mu;
  }
  json smallest = minimal();
  smallest["volume_ml"] = 1e-3;
  EXPECT_EQ(errorOf(smallest), "");
}

// Issue 21, second corpus: a key given twice in one object (the parser kept the last, silently), and the upper
// ends of volume_ml (1000 ml, past any vertebra) and flow_rate_ml_per_s (1000 ml/s): a volume of 1e308 was
// blamed on the flow rate ("takes inf s"). Each refusal is one line naming the file and the key at fault.
TEST(SceneConfig, DuplicateKeysAndVolumesOrRatesPastAnyInjectionAreRefusedNamingTheKey) {
  const auto dir = std::filesystem::temp_directory_path() / "cementsph-scene-duplicates";
  std::filesystem::create_directories(dir);
  const auto path = (dir / "scene.json").string();
  auto errorOf = [&](const std::string& text) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
    try {
      (void)loadSceneFile(path);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string tip = R"("tip_mm": [4, 5, 6])";
  for (const auto& [text, key] : std::vector<std::pair<std::string, std::string>>{
           {"{" + tip + R"(, "volume_ml": 1, "volume_ml": 2})", "volume_ml"},
           {"{" + tip + R"(, "cement": "x", "tip_mm": [1, 2, 3]})", "tip_mm"},
           {"{" + tip + R"(, "volume_ml": 1e308})", "volume_ml"},
           {"{" + tip + R"(, "volume_ml": 1000.5})", "volume_ml"},
           {"{" + tip + R"(, "flow_rate_ml_per_s": 1e308})", "flow_rate_ml_per_s"},
           // Thinner than water: the time step had no bound and the error named no key.
           {"{" + tip + R"(, "viscosity_pa_s": 1e-300})", "viscosity_pa_s"}}) {
    const std::string e = errorOf(text);
    EXPECT_EQ(e.rfind(path + ": ", 0), 0u) << text << ": " << e;
    EXPECT_NE(e.find("'" + key + "'"), std::string::npos) << text << ": " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    if (key != "flow_rate_ml_per_s") {
      EXPECT_EQ(e.find("flow_rate_ml_per_s"), std::string::npos) << e;
    }
  }
  // The same key in two different objects is not a duplicate, and the limits themselves are accepted.
  EXPECT_EQ(errorOf("{" + tip + R"(, "volume_ml": 1000, "flow_rate_ml_per_s": 1000, "viscosity_pa_s": 1e-4})"),
            "no error");
  EXPECT_EQ(errorOf("{" + tip + R"(, "label_table": {"1": "bone"}, "labels_path": "x.nrrd"})").find("appears twice"),
            std::string::npos);
}

// A FIFO with no writer would block the open forever, a folder reads as nothing: both refused at once naming
// the path (the test would hang, not fail, if the FIFO were opened).
TEST(SceneConfig, AFifoOrFolderGivenAsTheSceneIsRefusedWithoutOpeningIt) {
  const auto dir = std::filesystem::temp_directory_path() / "cementsph-scene-fifo";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string fifo = (dir / "scene.json").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& path : {fifo, dir.string()}) {
    try {
      (void)loadSceneFile(path);
      ADD_FAILURE() << path << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + ": not a regular file", 0), 0u) << e.what();
    }
  }
}

// snapshot_arrays: "growth" unless set, "flow" taken, anything else refused naming the key and the two values;
// the scene as run (toJson) says which.
TEST(SceneConfig, SnapshotArraysIsGrowthOrFlow) {
  EXPECT_EQ(SceneConfig{}.snapshotArrays, "growth");
  SceneConfig s;
  applySceneJson(s, json{{"snapshot_arrays", "flow"}});
  EXPECT_EQ(s.snapshotArrays, "flow");
  EXPECT_EQ(toJson(s)["snapshot_arrays"], "flow");
  try {
    applySceneJson(s, json{{"snapshot_arrays", "all"}});
    ADD_FAILURE() << "\"all\" taken";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("snapshot_arrays"), std::string::npos) << what;
    EXPECT_NE(what.find("\"growth\""), std::string::npos) << what;
    EXPECT_NE(what.find("\"flow\""), std::string::npos) << what;
  }
}
