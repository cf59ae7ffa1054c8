// The study's plan (StudyPlan.h): which run is the reference, the run order, and the option checks.
#include "cementsph/study/StudyPlan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

using namespace cementsph;
using study::StudyPlan;
using study::StudyRunSpec;

namespace {

StudyPlan plan() {
  StudyPlan p;
  p.baseScene = scene::scenePreset("paper");
  p.baseScene.tipMm = Eigen::Vector3d(10, 10, 10);
  return p;
}

// The message of the std::invalid_argument validate() throws, or "" if it does not throw.
std::string refusal(StudyPlan p) {
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

} // namespace

TEST(StudyPlan, DefaultsAreThePapersRadiiWithBothIntegrators) {
  StudyPlan p = plan();
  p.validate();
  EXPECT_EQ(p.radiiMm, (std::vector<double>{1.00, 0.75, 0.57, 0.50, 0.45}));
  EXPECT_EQ(p.integrators, (std::vector<std::string>{"overdamped", "central-difference"}));
  EXPECT_EQ(p.sizeRuns().size(), 10u);
  EXPECT_TRUE(p.viscosityRuns().empty());
}

TEST(StudyPlan, ReferenceIsTheSmallestRadiusWithCentralDifferenceAndRunsFirst) {
  StudyPlan p = plan();
  p.validate();
  const auto runs = p.sizeRuns();
  ASSERT_FALSE(runs.empty());
  EXPECT_TRUE(runs[0].reference);
  EXPECT_EQ(runs[0].integrator, "central-difference");
  EXPECT_DOUBLE_EQ(runs[0].particleRadiusMm, 0.45);
  EXPECT_EQ(std::count_if(runs.begin(), runs.end(), [](const StudyRunSpec& r) { return r.reference; }), 1);
  // The others keep the order given: integrators, then radii.
  EXPECT_EQ(runs[1].integrator, "overdamped");
  EXPECT_DOUBLE_EQ(runs[1].particleRadiusMm, 1.00);
  EXPECT_EQ(runs[9].integrator, "central-difference");
  EXPECT_DOUBLE_EQ(runs[9].particleRadiusMm, 0.50);
}

TEST(StudyPlan, WithoutCentralDifferenceTheNextMostFaithfulIsTheReference) {
  StudyPlan p = plan();
  p.radiiMm = {0.5, 0.8};
  p.integrators = {"overdamped", "explicit"};
  p.validate();
  EXPECT_EQ(p.sizeRuns()[0].integrator, "explicit");
  EXPECT_DOUBLE_EQ(p.sizeRuns()[0].particleRadiusMm, 0.5);
  p.integrators = {"overdamped"};
  p.validate();
  EXPECT_TRUE(p.sizeRuns()[0].reference);
  EXPECT_EQ(p.sizeRuns()[0].integrator, "overdamped");
  EXPECT_GT(study::integratorFaithfulness("central-difference"), study::integratorFaithfulness("explicit"));
  EXPECT_GT(study::integratorFaithfulness("explicit"), study::integratorFaithfulness("overdamped"));
}

TEST(StudyPlan, ACtReferenceLeavesNoRunAsReference) {
  StudyPlan p = plan();
  p.referenceIsCt = true;
  p.validate();
  for (const StudyRunSpec& r : p.sizeRuns()) EXPECT_FALSE(r.reference);
  EXPECT_EQ(p.sizeRuns()[0].integrator, "overdamped"); // plain order
  EXPECT_DOUBLE_EQ(p.sizeRuns()[0].particleRadiusMm, 1.00);
}

TEST(StudyPlan, RunScenesCarryRadiusIntegratorAndViscosity) {
  StudyPlan p = plan();
  p.integrators = {"paper"}; // the engine's alias for central-difference
  p.viscositiesPaS = {50, 400};
  p.validate();
  EXPECT_EQ(p.integrators[0], "central-difference");
  const scene::SceneConfig s = p.sizeRuns()[3].scene(p.baseScene); // after the reference: 1.00, 0.75, 0.57
  EXPECT_DOUBLE_EQ(s.particleRadiusMm, 0.57);
  EXPECT_EQ(*s.integrator, "central-difference");
  EXPECT_DOUBLE_EQ(s.viscosityPaS, 100.0);
  const auto sweep = p.viscosityRuns();
  ASSERT_EQ(sweep.size(), 2u);
  EXPECT_DOUBLE_EQ(sweep[1].scene(p.baseScene).viscosityPaS, 400.0);
  EXPECT_DOUBLE_EQ(sweep[1].particleRadiusMm, 0.57); // the scene's radius
  EXPECT_EQ(sweep[1].integrator, "overdamped");       // the scene's model preset's integrator
  EXPECT_EQ(sweep[1].name(), "viscosity_400pa_s");
  EXPECT_EQ(p.sizeRuns()[0].name(), "central-difference_r0.45mm");
}

TEST(StudyPlan, BadOptionsAreOneLineNamingTheOption) {
  auto expectRefused = [](StudyPlan p, const std::string& words) {
    const std::string message = refusal(std::move(p));
    EXPECT_NE(message.find(words), std::string::npos) << "'" << message << "' lacks '" << words << "'";
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  };
  StudyPlan p = plan();
  p.radiiMm = {0.5, -1};
  expectRefused(p, "--radii-mm: -1 is not a positive number");
  p = plan();
  p.radiiMm = {0.5, 0.5};
  expectRefused(p, "--radii-mm: 0.5 is given twice");
  p = plan();
  p.radiiMm = {};
  expectRefused(p, "--radii-mm: no radius");
  p = plan();
  p.integrators = {"leapfrog"};
  expectRefused(p, "--integrators: unknown integrator 'leapfrog'");
  p = plan();
  p.integrators = {"paper", "central-difference"};
  expectRefused(p, "--integrators: central-difference is given twice");
  p = plan();
  p.viscositiesPaS = {100, 0};
  expectRefused(p, "--viscosities-pa-s: 0 is not a positive number");
  p = plan();
  p.viscositiesPaS = {100};
  p.baseScene.viscosityRatePaPerS = 2.0;
  expectRefused(p, "viscosity_rate_pa_per_s");
  p = plan();
  p.sizeStudy = false;
  expectRefused(p, "nothing to run");
  p = plan();
  p.baseScene.tipMm.reset();
  expectRefused(p, "tip_mm");
  p = plan();
  p.radiiMm = {std::numeric_limits<double>::quiet_NaN()};
  expectRefused(p, "is not a positive number");
}
