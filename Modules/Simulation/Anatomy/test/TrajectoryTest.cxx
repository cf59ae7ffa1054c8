// anatomy::checkTrajectory's rule (Trajectory.h) on a hand-made anatomy: a row of voxels whose classes are set
// here, so every crossing's depth is known exactly. Samples are every 0.25 mm and take their nearest voxel
// (1 mm voxels centred on whole millimetres: the sample at depth d is in voxel lround(d), halves rounding up),
// so a run of voxels a..b is seen from depth a - 0.5 to b + 0.25.
#include "cementsph/anatomy/Trajectory.h"

#include <gtest/gtest.h>

#include <map>

namespace {
using namespace cementsph::anatomy;

// A 30 x 1 x 1 row of 1 mm voxels; voxel x has class classes(x).
Anatomy row(const std::map<int, TissueClass>& runsFrom) {
  Anatomy a;
  a.grid.size = {30, 1, 1};
  a.rule = "test";
  a.targetFound = true;
  TissueClass c = TissueClass::OtherSoftTissue;
  for (int x = 0; x < 30; ++x) {
    if (runsFrom.count(x)) c = runsFrom.at(x);
    a.classes.push_back(std::uint8_t(c));
  }
  return a;
}

TEST(Trajectory, ApproachSeamCanalAndBreachAsTheRuleSays) {
  // 0-4 soft tissue (the approach), 5-9 vertebra, 10 one soft voxel (a seam), 11-14 vertebra, 15-17 canal,
  // 18-19 vertebra, 20-22 soft tissue (a breach, 3 mm), 23-29 vertebra.
  const Anatomy a = row({{0, TissueClass::OtherSoftTissue}, {5, TissueClass::TargetVertebra},
                         {10, TissueClass::OtherSoftTissue}, {11, TissueClass::TargetVertebra},
                         {15, TissueClass::Canal}, {18, TissueClass::TargetVertebra},
                         {20, TissueClass::OtherSoftTissue}, {23, TissueClass::TargetVertebra}});
  const TrajectoryCheck c = checkTrajectory(a, {0, 0, 0}, {29, 0, 0});
  EXPECT_DOUBLE_EQ(c.lengthMm, 29.0);
  EXPECT_DOUBLE_EQ(c.stepMm, 0.25);
  EXPECT_DOUBLE_EQ(c.reachesVertebraMm, 4.5);
  ASSERT_EQ(c.crossings.size(), 2u) << c.message; // the approach and the seam are not crossings
  EXPECT_EQ(c.crossings[0].kind, "canal");
  EXPECT_DOUBLE_EQ(c.crossings[0].fromDepthMm, 14.5);
  EXPECT_DOUBLE_EQ(c.crossings[0].toDepthMm, 17.25);
  EXPECT_DOUBLE_EQ(c.crossings[0].firstMm[0], 14.5);
  EXPECT_EQ(c.crossings[1].kind, "cortex_breach");
  EXPECT_DOUBLE_EQ(c.crossings[1].fromDepthMm, 19.5);
  EXPECT_DOUBLE_EQ(c.crossings[1].toDepthMm, 22.25);
  EXPECT_EQ(c.verdict, "refused");
  EXPECT_NE(c.message.find("spinal canal 14.5 to 17.2"), std::string::npos) << c.message;
}

TEST(Trajectory, ADiscIsAWarningAndOneVoxelDoesNotSplitACrossing) {
  // 0-9 vertebra, 10-11 disc, 12 vertebra (one voxel: the disc goes on), 13-14 disc, 15-29 vertebra.
  const Anatomy a = row({{0, TissueClass::TargetVertebra}, {10, TissueClass::Disc}, {12, TissueClass::TargetVertebra},
                         {13, TissueClass::Disc}, {15, TissueClass::TargetVertebra}});
  const TrajectoryCheck c = checkTrajectory(a, {0, 0, 0}, {29, 0, 0});
  ASSERT_EQ(c.crossings.size(), 1u) << c.message;
  EXPECT_EQ(c.crossings[0].kind, "disc");
  EXPECT_DOUBLE_EQ(c.crossings[0].fromDepthMm, 9.5);
  EXPECT_DOUBLE_EQ(c.crossings[0].toDepthMm, 14.25);
  EXPECT_EQ(c.verdict, "warning");
}

TEST(Trajectory, ClearWhenTheShaftStaysInTheVertebraAndUncheckedWithoutOne) {
  Anatomy a = row({{0, TissueClass::OtherSoftTissue}, {3, TissueClass::TargetVertebra}});
  const TrajectoryCheck c = checkTrajectory(a, {0, 0, 0}, {29, 0, 0});
  EXPECT_EQ(c.verdict, "clear");
  EXPECT_TRUE(c.crossings.empty());
  // A deepest tip out of the bone at the shaft's end is a breach however short.
  const TrajectoryCheck out = checkTrajectory(row({{0, TissueClass::TargetVertebra}, {29, TissueClass::OtherSoftTissue}}),
                                              {0, 0, 0}, {29, 0, 0});
  ASSERT_EQ(out.crossings.size(), 1u);
  EXPECT_EQ(out.crossings[0].kind, "cortex_breach");
  a.targetFound = false;
  EXPECT_EQ(checkTrajectory(a, {0, 0, 0}, {29, 0, 0}).verdict, "unchecked");
  EXPECT_THROW(checkTrajectory(a, {1, 2, 3}, {1, 2, 3}), std::invalid_argument);
}

} // namespace
