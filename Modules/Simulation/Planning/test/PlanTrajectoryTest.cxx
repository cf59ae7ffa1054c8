// plan's trajectory check (PlanTrajectory.h, issue 20 item 4) on the vertebra phantom (VertebraPhantom.h) with
// the CT bone rule. The oracle is the phantom's analytic geometry, written out here from its documented layout:
// field 64 x 70 x 45 mm of 1 x 1 x 1.5 mm voxels; the body an elliptic cylinder about (32, 21, 22.5) mm, semi-axes
// 20 x 15 mm; the canal a cylinder of radius 8 mm about (32, 44) in x, y, within 10 mm of mid height; the
// posterior arch (pedicles and lamina) the ring 8 .. 12 mm about the canal's axis with y >= 35.5 mm.
#include "cementsph/phantom/VertebraPhantom.h"
#include "cementsph/planning/InjectionPlanner.h"
#include "cementsph/planning/PlanTrajectory.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {
using namespace cementsph;

const Eigen::Vector3d kCanalAxis(32, 44, 22.5);
constexpr double kCanalR = 8.0;

planning::PlanRequest request(const Eigen::Vector3d& entry, const Eigen::Vector3d& target) {
  planning::PlanRequest r;
  r.entryMm = entry;
  r.targetCentreMm = target;
  r.direction = target - entry; // as `plan` without --direction
  r.maxDepthMm = (target - entry).norm();
  return r;
}

const imaging::ImageType* phantomCt() {
  static const phantom::VertebraResult v = phantom::makeVertebra({});
  return v.ct.GetPointer();
}

// The depth along entry -> target at which the line first meets the canal's cylinder (radius 8 about its axis).
double analyticCanalDepth(const Eigen::Vector3d& entry, const Eigen::Vector3d& target) {
  const Eigen::Vector2d p(entry.x() - kCanalAxis.x(), entry.y() - kCanalAxis.y());
  const Eigen::Vector2d d = Eigen::Vector2d(target.x() - entry.x(), target.y() - entry.y()).normalized();
  const double b = p.dot(d), c = p.squaredNorm() - kCanalR * kCanalR;
  return -b - std::sqrt(b * b - c); // the line lies in the axial plane z = 22.5, so depth in x, y is depth
}

// Through the arch's lateral side into the body: the line's nearest approach to the canal's axis is 10.7 mm
// (worked out by hand: 2.7 mm clear of the canal, inside the 12 mm ring), so nothing is crossed.
TEST(PlanTrajectory, ATranspedicularEntryPasses) {
  const Eigen::Vector3d entry(48.5, 52.4, 22.5), target(32, 21, 22.5);
  const auto r = request(entry, target);
  const anatomy::TrajectoryCheck c = planning::checkPlanTrajectory(phantomCt(), r);
  EXPECT_EQ(c.verdict, "clear") << c.message;
  EXPECT_EQ(c.rule, "ct-bone-rule");
  EXPECT_NEAR(c.lengthMm, (target - entry).norm(), 1e-9);
  EXPECT_GT(c.reachesVertebraMm, 0.0) << c.message; // the approach through the soft tissue behind the arch
  EXPECT_NO_THROW(planning::requireASafeTrajectory(c, r));
}

// From behind, in the midline: lamina, then the canal from y = 44 + 8 = 52 mm (depth 10 mm), refused.
TEST(PlanTrajectory, AMidlineEntryThroughTheCanalIsRefusedWhereTheCanalBegins) {
  const Eigen::Vector3d entry(32, 62, 22.5), target(32, 21, 22.5);
  auto r = request(entry, target);
  const anatomy::TrajectoryCheck c = planning::checkPlanTrajectory(phantomCt(), r);
  ASSERT_EQ(c.verdict, "refused") << c.message;
  ASSERT_FALSE(c.crossings.empty());
  const auto& canal = c.crossings.front();
  EXPECT_EQ(canal.kind, "canal");
  // The line meets the canal's wall square on, so the position's error is the boundary's: within one voxel.
  const Eigen::Vector3d first(canal.firstMm[0], canal.firstMm[1], canal.firstMm[2]);
  EXPECT_LE((first - Eigen::Vector3d(32, 52, 22.5)).norm(), 1.0) << first.transpose();
  EXPECT_NEAR(canal.fromDepthMm, analyticCanalDepth(entry, target), 1.0);
  try {
    planning::requireASafeTrajectory(c, r);
    ADD_FAILURE() << "not refused";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("spinal canal"), std::string::npos) << m;
    EXPECT_NE(m.find("--allow-canal-crossing"), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
  r.allowCanalCrossing = true;
  EXPECT_NO_THROW(planning::requireASafeTrajectory(c, r));
}

// The phantom's suggested direction (-0.3, -0.954, 0) from 20 mm behind its suggested tip grazes the canal's
// lateral edge (entering it at about 25 degrees): flagged. At that angle an error of a voxel across the canal's
// wall moves the crossing along the line by up to 1 / sin(25 deg) = 2.4 voxels, so the check is on the first
// sample's distance from the canal's axis: within one voxel (1 mm in x, y) of the wall, 8 mm.
TEST(PlanTrajectory, AnObliqueEntryWhoseLineCrossesTheCanalIsFlagged) {
  const Eigen::Vector3d entry(41, 49.08, 22.5), target(32, 21, 22.5);
  const anatomy::TrajectoryCheck c = planning::checkPlanTrajectory(phantomCt(), request(entry, target));
  ASSERT_EQ(c.verdict, "refused") << c.message;
  const auto& canal = c.crossings.front();
  EXPECT_EQ(canal.kind, "canal");
  const double fromAxis = std::hypot(canal.firstMm[0] - kCanalAxis.x(), canal.firstMm[1] - kCanalAxis.y());
  EXPECT_NEAR(fromAxis, kCanalR, 1.0);
  EXPECT_NEAR(canal.fromDepthMm, analyticCanalDepth(entry, target), 2.4);
}

} // namespace
