// The study's runs go through vtkSPHInjectionFilter (issue 22 item 1) and are checked before any starts (item 2).
// Oracle for the first: the inject runner itself (runInjection, InjectionRunner.h) on the same CT and scene,
// run directly: the filter's simulated CT must hold the driver's simulated CT voxel for voxel inside the region
// of interest and the CT's own HU outside it (exactly: the paste-back of an axial CT moves no value), and the
// run's figures must be the driver's (every metrics.json key but the wall times). Oracle for the second: the
// porous solid's own refusals (a strut voxel of the phantom is solid; a point 500 mm away is outside the CT).
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/parallel/CaseFarm.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/study/StudyRunner.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <stdexcept>

using namespace cementsph;

namespace {

const std::filesystem::path kPhantom = std::filesystem::path(CEMENTSPH_TEST_DATA_DIR) / "foam-phantom";

study::StudyPlan phantomPlan(double radiusMm) {
  std::ifstream in(kPhantom / "truth.json");
  const auto tip = nlohmann::json::parse(in).at("injection").at("tip_mm");
  study::StudyPlan plan;
  plan.baseScene = scene::scenePreset("paper");
  plan.baseScene.tipMm = Eigen::Vector3d(tip[0].get<double>(), tip[1].get<double>(), tip[2].get<double>());
  plan.baseScene.volumeMl = 0.05;
  plan.radiiMm = {radiusMm};
  plan.integrators = {"overdamped"};
  plan.validate();
  return plan;
}

// The metrics with the keys that time the machine, not the run, removed.
nlohmann::json withoutWallTimes(nlohmann::json m) {
  for (const char* key : {"wall_time_s", "real_time_factor", "timing", "provenance"}) m.erase(key);
  return m;
}

} // namespace

TEST(StudyThroughFilter, FilterRunEqualsTheDriversRunOnTheSameScene) {
  const auto ct = imaging::readVolume((kPhantom / "pre.nrrd").string());
  const study::StudyPlan plan = phantomPlan(0.75);
  const study::StudyRunSpec spec = plan.sizeRuns().at(0);
  const study::StudyRunner runner(ct, plan);
  const study::SimulatedRun viaFilter = runner.simulate(spec);
  ASSERT_TRUE(viaFilter.failure.empty()) << viaFilter.failure;
  ASSERT_TRUE(viaFilter.simulatedCt);

  const scene::InjectionRunResult direct = scene::runInjection(ct, spec.scene(plan.baseScene), {});
  ASSERT_TRUE(direct.simulatedCt);
  EXPECT_EQ(withoutWallTimes(viaFilter.metrics), withoutWallTimes(direct.metrics));

  // On the CT's own grid.
  const auto& filtered = *viaFilter.simulatedCt;
  EXPECT_EQ(filtered.GetLargestPossibleRegion().GetSize(), ct->GetLargestPossibleRegion().GetSize());
  for (unsigned a = 0; a < 3; ++a) {
    EXPECT_NEAR(filtered.GetOrigin()[a], ct->GetOrigin()[a], 1e-9);
    EXPECT_NEAR(filtered.GetSpacing()[a], ct->GetSpacing()[a], 1e-12);
  }
  // Inside the region: the driver's simulated CT; outside: the CT.
  const auto& region = *direct.simulatedCt;
  std::size_t inside = 0, risen = 0;
  const auto size = ct->GetLargestPossibleRegion().GetSize();
  for (long z = 0; z < long(size[2]); ++z)
    for (long y = 0; y < long(size[1]); ++y)
      for (long x = 0; x < long(size[0]); ++x) {
        const imaging::ImageType::IndexType i{{x, y, z}};
        imaging::ImageType::PointType p;
        ct->TransformIndexToPhysicalPoint(i, p);
        imaging::ImageType::IndexType j;
        const float got = filtered.GetPixel(i);
        if (region.TransformPhysicalPointToIndex(p, j)) {
          ++inside;
          ASSERT_EQ(got, region.GetPixel(j)) << "region voxel " << j;
          if (got > ct->GetPixel(i)) ++risen;
        } else {
          ASSERT_EQ(got, ct->GetPixel(i)) << "voxel " << i << " outside the region";
        }
      }
  EXPECT_EQ(inside, region.GetLargestPossibleRegion().GetNumberOfPixels());
  EXPECT_GT(risen, 0u); // the injection shows
}

TEST(StudyThroughFilter, EveryRunIsCheckedBeforeAnyStarts) {
  const auto ct = imaging::readVolume((kPhantom / "pre.nrrd").string());
  study::StudyPlan plan = phantomPlan(0.75);
  plan.radiiMm = {1.0, 0.75};
  plan.integrators = {"overdamped", "central-difference"};
  plan.validate();
  EXPECT_NO_THROW(study::checkRunsCanStart(ct, plan));

  plan.baseScene.tipMm = Eigen::Vector3d(9.0, 22.09, 22.0); // a strut of the phantom (600 HU)
  try {
    study::checkRunsCanStart(ct, plan);
    ADD_FAILURE() << "a tip in solid passed the check";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lies in solid"), std::string::npos) << e.what();
  }
  plan.baseScene.tipMm = Eigen::Vector3d(500.0, 22.0, 22.0);
  try {
    study::checkRunsCanStart(ct, plan);
    ADD_FAILURE() << "a tip outside the CT passed the check";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lies outside the CT"), std::string::npos) << e.what();
  }
}

TEST(StudyThroughFilter, RunStartsAreAnnouncedBeforeTheirResults) {
  const auto ct = imaging::readVolume((kPhantom / "pre.nrrd").string());
  study::StudyPlan plan = phantomPlan(1.0);
  plan.viscositiesPaS = {100.0};
  plan.validate();
  study::StudyRunner runner(ct, plan);
  std::vector<std::string> events;
  runner.runStudy(
      parallel::caseFarm(), [&](const std::vector<study::StudyRow>& rows, std::size_t) { events.push_back("done " + rows.back().spec.name()); },
      [&](const study::StudyRunSpec& run, std::size_t index, std::size_t planned) {
        EXPECT_EQ(planned, 2u);
        events.push_back("start " + std::to_string(index) + " " + run.name());
      });
  EXPECT_EQ(events, (std::vector<std::string>{"start 0 overdamped_r1.00mm", "done overdamped_r1.00mm",
                                              "start 1 viscosity_100pa_s", "done viscosity_100pa_s"}));
}
