// The cannula's direction on a patient CT (issue 20 item 4, issue 21): where the tip lies in a vertebra (uniform
// trabecular bone, 150 HU, walled by 1000 HU cortex: what the anatomy takes for a vertebral body), the default
// [0, 0, 1] would put the shaft straight up through the endplate below, so a scene without `direction` is
// refused with one line naming the key; the same scene with the direction given runs, whatever its value (a
// direction set in code, as a plan's trajectory, counts as given). The synthetic phantoms keep the default by
// design: on the porous scaffold (no vertebra) the scene without a direction runs. Tiny runs (0.02-0.05 ml).
#include "cementsph/scene/InjectionRunner.h"
#include "ScaffoldCT.h"

#include <gtest/gtest.h>

#include <string>

using namespace cementsph;
using namespace cementsph::scene;

namespace {

// 40^3 voxels of 0.5 mm: a 2-voxel cortical shell (1000 HU) around trabecular bone (150 HU).
imaging::ImageType::Pointer vertebralBody() {
  auto img = scene::testing::cube(40, 0.5, 150.f);
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        auto edge = [](int x) { return x <= 1 || x >= 38; };
        if (edge(i) || edge(j) || edge(k)) img->SetPixel({{i, j, k}}, 1000.f);
      }
  return img;
}

nlohmann::json sceneAtCentre() {
  return {{"tip_mm", {10, 10, 10}}, {"volume_ml", 0.05}, {"flow_rate_ml_per_s", 0.05}, {"snapshot_interval_s", 1.0},
          {"cannula_length_mm", 5}};
}

} // namespace

TEST(CannulaDirection, APatientCtWithoutADirectionIsRefusedNamingTheKey) {
  try {
    (void)runInjection(vertebralBody(), sceneFromJson(sceneAtCentre()), {});
    FAIL() << "a scene without direction ran on a vertebra";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("scene: key 'direction' is missing", 0), 0u) << what;
    EXPECT_NE(what.find("vertebra"), std::string::npos) << what;
    EXPECT_NE(what.find("--set direction="), std::string::npos) << what; // what to do
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(CannulaDirection, AGivenDirectionRunsEvenTheDefaultsValue) {
  nlohmann::json j = sceneAtCentre();
  j["direction"] = {0, 0, 1};
  const InjectionRunResult given = runInjection(vertebralBody(), sceneFromJson(j), {});
  EXPECT_EQ(given.summary.boneModel, "continuum") << given.summary.boneModelReason;
  EXPECT_NEAR(given.summary.volumeInjectedMl, 0.05, 1e-9);
  // Set in code (a plan's trajectory from behind: anterior, -y in LPS).
  SceneConfig inCode = sceneFromJson(sceneAtCentre());
  inCode.direction = Eigen::Vector3d(0, -1, 0);
  EXPECT_NEAR(runInjection(vertebralBody(), inCode, {}).summary.volumeInjectedMl, 0.05, 1e-9);
  // Set in code to the default's value, recorded as given (what plan does with its trajectory).
  SceneConfig upward = sceneFromJson(sceneAtCentre());
  upward.direction = Eigen::Vector3d::UnitZ();
  upward.explicitKeys.insert("direction");
  EXPECT_NEAR(runInjection(vertebralBody(), upward, {}).summary.volumeInjectedMl, 0.05, 1e-9);
}

TEST(CannulaDirection, ThePorousScaffoldKeepsTheDefault) {
  nlohmann::json j = sceneAtCentre();
  j["tip_mm"] = {13, 13, 13};
  j["volume_ml"] = 0.02;
  const InjectionRunResult r = runInjection(scene::testing::scaffold(), sceneFromJson(j), {});
  EXPECT_EQ(r.summary.boneModel, "pore-resolved");
  EXPECT_NEAR(r.summary.volumeInjectedMl, 0.02, 1e-9);
}
