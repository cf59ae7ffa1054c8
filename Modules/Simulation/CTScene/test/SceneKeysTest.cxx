// Scene keys the chosen engine does not read are never ignored silently (issue 21): each one the user set is a
// warning in metrics.json naming the key, the engine and why that engine was chosen. Which keys are whose is
// written here from each key's documented meaning (SceneConfig.h), not read from the registry:
//   solid_mass_factor     the fixed particles' mass: only the SPH particle engines (incompressible,
//                         equation-of-state) have fixed particles
//   integrator, neighbour_skin_over_h   the SPH particles' time integration and neighbour lists: the same two
//   sound_speed_m_per_s   the equation of state's c_s: the same two; and pressure_model "auto" reads it to choose
//   capillary_tension_n_per_m, pore_permeability_m2   documented "voxel-darcy:" (the pore permeability also
//                         particle-darcy's, VALIDATION.md)
//   volume_ml, flow_rate_ml_per_s, cannula_length_mm   what every engine injects, and where
// The runs are the voxel engine's on the 20 mm scaffold CT (ScaffoldCT.h), 0.02 ml: well under a second each.
#include "cementsph/scene/InjectionModel.h"
#include "cementsph/scene/InjectionRunner.h"
#include "ScaffoldCT.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

using namespace cementsph;
using namespace cementsph::scene;
using nlohmann::json;

namespace {

// A tiny injection on the scaffold with `extra` keys set (as a scene file sets them).
json tinyScene(const json& extra) {
  json j{{"tip_mm", {13, 13, 13}},
         {"volume_ml", 0.02},
         {"flow_rate_ml_per_s", 0.01},
         {"snapshot_interval_s", 1.0},
         {"cannula_length_mm", 5}};
  j.update(extra);
  return j;
}

InjectionResult run(const json& extra) { return runInjection(scene::testing::scaffold(), sceneFromJson(tinyScene(extra)), {}); }

// The key each warning names ("scene key K does not apply ...").
std::set<std::string> keysWarnedOf(const std::vector<std::string>& warnings) {
  std::set<std::string> keys;
  const std::string head = "scene key ";
  for (const std::string& w : warnings)
    if (w.rfind(head, 0) == 0) keys.insert(w.substr(head.size(), w.find(' ', head.size()) - head.size()));
  return keys;
}

} // namespace

// solid_mass_factor under the voxel engine: exactly one warning, word for word, and the same in metrics.json.
TEST(SceneKeys, AParticleOnlyKeyUnderTheVoxelEngineIsAWarning) {
  const InjectionResult r = run({{"pressure_model", "voxel-darcy"}, {"solid_mass_factor", 4.0}});
  ASSERT_EQ(r.summary.engine, "voxel-darcy");
  const std::vector<std::string> expected{
      "scene key solid_mass_factor does not apply to the voxel-darcy model (chosen: set by the scene key "
      "pressure_model); it was ignored (it is read by: equation-of-state, incompressible)"};
  EXPECT_EQ(r.summary.warnings, expected);
  EXPECT_EQ(r.metrics.at("warnings"), json(expected));
}

// Several particle keys: one warning each; keys the voxel engine reads (its own, and what every engine injects):
// none.
TEST(SceneKeys, OneWarningPerKeyTheEngineDoesNotReadAndNoneForTheKeysItReads) {
  const InjectionResult r = run({{"pressure_model", "voxel-darcy"},
                                 {"integrator", "overdamped"},
                                 {"neighbour_skin_over_h", 0.3},
                                 {"sound_speed_m_per_s", 0.5},
                                 {"capillary_tension_n_per_m", 0.01},
                                 {"pore_permeability_m2", 1e-9}});
  EXPECT_EQ(keysWarnedOf(r.summary.warnings),
            (std::set<std::string>{"integrator", "neighbour_skin_over_h", "sound_speed_m_per_s"}))
      << r.metrics.at("warnings").dump();
  EXPECT_EQ(r.summary.warnings.size(), 3u) << r.metrics.at("warnings").dump();

  const InjectionResult readOnly = run({{"pressure_model", "voxel-darcy"},
                                     {"capillary_tension_n_per_m", 0.01},
                                     {"pore_permeability_m2", 1e-9}});
  EXPECT_TRUE(readOnly.summary.warnings.empty()) << readOnly.metrics.at("warnings").dump();
}

// pressure_model "auto": the sound speed decided the choice (the compression number), so it was not ignored; the
// solid mass factor was, and the warning says the automatic choice picked the engine, and on what ground.
TEST(SceneKeys, UnderAutoTheWarningNamesTheAutomaticChoice) {
  const InjectionResult r = run({{"sound_speed_m_per_s", 0.5}, {"solid_mass_factor", 4.0}});
  ASSERT_EQ(r.summary.engine, "voxel-darcy") << r.summary.modelReason;
  ASSERT_EQ(r.summary.warnings.size(), 1u) << r.metrics.at("warnings").dump();
  EXPECT_EQ(r.summary.warnings[0],
            "scene key solid_mass_factor does not apply to the voxel-darcy model (chosen: pressure_model \"auto\" "
            "chose it: creeping flow); it was ignored (it is read by: equation-of-state, incompressible)");
}

// A key set to the value it has anyway (solid_mass_factor 8, the documented default) changes nothing whatever
// the engine: no warning (a recorded scene.json lists it always).
TEST(SceneKeys, AKeyAtItsDefaultValueIsNoWarning) {
  const InjectionResult r = run({{"pressure_model", "voxel-darcy"}, {"solid_mass_factor", 8.0}});
  EXPECT_TRUE(r.summary.warnings.empty()) << r.metrics.at("warnings").dump();
}

// The other way round, without a run: a voxel-only key under the equation of state.
TEST(SceneKeys, AVoxelOnlyKeyUnderAParticleEngine) {
  const SceneConfig scene =
      sceneFromJson(tinyScene({{"pressure_model", "equation-of-state"}, {"capillary_tension_n_per_m", 0.01}}));
  ModelChoice choice;
  choice.pressureModel = "equation-of-state";
  choice.reason = "forced by the scene key pressure_model (Re = 1)";
  const std::vector<std::string> expected{
      "scene key capillary_tension_n_per_m does not apply to the equation-of-state model (chosen: set by the scene "
      "key pressure_model); it was ignored (it is read by: voxel-darcy)"};
  EXPECT_EQ(sceneKeysNotRead(scene, "equation-of-state", choice), expected);
  // pore_permeability_m2 is particle-darcy's as well as voxel-darcy's.
  const SceneConfig permeable =
      sceneFromJson(tinyScene({{"pressure_model", "incompressible"}, {"pore_permeability_m2", 1e-9}}));
  choice.pressureModel = "incompressible";
  const std::vector<std::string> both{
      "scene key pore_permeability_m2 does not apply to the incompressible model (chosen: set by the scene key "
      "pressure_model); it was ignored (it is read by: particle-darcy, voxel-darcy)"};
  EXPECT_EQ(sceneKeysNotRead(permeable, "incompressible", choice), both);
  // A field set in code is not a key the user set.
  SceneConfig inCode = sceneFromJson(tinyScene(json::object()));
  inCode.solidMassFactor = 4;
  choice.pressureModel = "voxel-darcy";
  EXPECT_TRUE(sceneKeysNotRead(inCode, "voxel-darcy", choice).empty());
}

// Every scene key is read by some engine or by the driver, and an engine's declaration names scene keys only
// (a misspelt key would otherwise be reported unread in every run).
TEST(SceneKeys, EveryKeyHasAReaderAndDeclarationsNameRealKeys) {
  const InjectionModelRegistry& registry = InjectionModelRegistry::instance();
  for (const std::string& key : sceneKeyNames()) {
    bool read = commonSceneKeys().count(key) > 0;
    for (const std::string& engine : registry.names())
      read = read || (registry.at(engine).sceneKeys && registry.at(engine).sceneKeys->count(key));
    EXPECT_TRUE(read) << key;
  }
  InjectionModelRegistry local;
  try {
    local.add("misspelt", [] { return std::unique_ptr<InjectionModel>(); }, "x", {"particle_radius"});
    FAIL() << "a declaration naming no scene key was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("\"particle_radius\", which is not a scene key"), std::string::npos) << e.what();
  }
}
