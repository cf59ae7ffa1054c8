// The plan the Planning suites make on the vertebra phantom (Testing/Data/vertebra-phantom): the paper's scene, the
// transpedicular entry (PlanTrajectoryTest: clear of the canal) aimed at a target in the body, the depth up to it.
#pragma once

#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/planning/InjectionPlanner.h"

#include <filesystem>

namespace cementsph::planning::testing {

inline imaging::ImageType::Pointer vertebraPhantomCt() {
  return imaging::readVolume((std::filesystem::path(CEMENTSPH_TEST_DATA_DIR) / "vertebra-phantom" / "pre.nrrd").string());
}

inline PlanRequest transpedicularRequest(const Eigen::Vector3d& targetMm = Eigen::Vector3d(32, 21, 22.5),
                                        const Eigen::Vector3d& entryMm = Eigen::Vector3d(48.5, 52.4, 22.5)) {
  PlanRequest r;
  r.scene = scene::scenePreset("paper");
  r.entryMm = entryMm;
  r.targetCentreMm = targetMm;
  r.direction = r.targetCentreMm - r.entryMm;
  r.maxDepthMm = r.direction.norm();
  return r;
}

} // namespace cementsph::planning::testing
