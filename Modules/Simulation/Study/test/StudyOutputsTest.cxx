// The study's tables and references (StudyOutputs.h), behind `cementsph study`: the finest run named as the
// paper defines it (smallest radius, most faithful integrator), study.json's counts and nulls from the record
// the test builds, the files written, and the wall time summed from rows whose times the test sets.
#include "cementsph/study/StudyOutputs.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

using namespace cementsph;

namespace {

namespace fs = std::filesystem;

study::StudyPlan plan() {
  study::StudyPlan p;
  p.baseScene = scene::scenePreset("paper");
  p.baseScene.tipMm = Eigen::Vector3d(10, 10, 10);
  p.validate();
  return p;
}

TEST(StudyOutputs, TheFinestRunIsTheSmallestRadiusWithTheMostFaithfulIntegrator) {
  const std::string reference = study::finestRunReference(plan());
  EXPECT_EQ(reference.rfind("the finest run, central-difference at r 0.45 mm", 0), 0u) << reference;
  study::StudyPlan noSize = plan();
  noSize.sizeStudy = false;
  EXPECT_EQ(study::finestRunReference(noSize), "");
}

TEST(StudyOutputs, RunsWallTimeIsTheSumOfInjectionAndAnalysisTimes) {
  study::StudyRecord record;
  record.sizeRows.resize(2);
  record.sizeRows[0].wallTimeS = 1.5;
  record.sizeRows[0].analysisTimeS = 0.25;
  record.sizeRows[1].wallTimeS = 2.0;
  record.viscosityRows.resize(1);
  record.viscosityRows[0].analysisTimeS = 0.5;
  EXPECT_DOUBLE_EQ(study::runsWallTimeS(record), 1.5 + 0.25 + 2.0 + 0.5);
}

TEST(StudyOutputs, TablesBeforeAnyRunAreTheMarkdownAndJsonWithZeroRunsDone) {
  const fs::path out = fs::temp_directory_path() / ("study_outputs_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const study::StudyPlan p = plan();
  study::StudyRecord record;
  record.ct = "ct.nrrd";
  record.sceneFile = "scene.json";
  record.plan = &p;
  record.reference = study::finestRunReference(p);
  record.thresholdRule = "above 500 HU";
  EXPECT_EQ(study::writeStudyTables(record, out), (std::vector<std::string>{"study.md", "study.json"}));
  EXPECT_TRUE(fs::exists(out / "study.md"));
  EXPECT_FALSE(fs::exists(out / "study.csv")); // no size row yet
  std::ifstream in(out / "study.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("size_runs_done").get<int>(), 0);
  EXPECT_TRUE(j.at("reference_ct").is_null());
  EXPECT_EQ(j.at("radii_mm").get<std::vector<double>>(), p.radiiMm);
  EXPECT_EQ(j.at("reference").get<std::string>(), record.reference);
  fs::remove_all(out);
}

} // namespace
