// X-ray sequences (paper Fig. 12): the cement segmented by subtracting the first frame's DRR, its projected
// area, and two sequences compared frame by frame. Oracles:
//  - a cement cylinder (3000 HU above soft tissue) of radius r and length L along the beam, at the isocentre,
//    thresholded at half its excess line integral (L dmu / 2): the edge of a partial-volume voxelised disc
//    at half height is unbiased, so the mask is the disc of radius r magnified by sid / sad in the plane of
//    the cylinder's middle: detector area pi r^2 (sid / sad)^2, isocentre area pi r^2; parallel beam pi r^2.
//    Within 1.5 % (0.25 mm pixels at the isocentre on a 10 mm disc; partial volumes in steps of 1/25);
//  - a cement ball of radius r at the default threshold (1 mm of water: chord c = 1/3 mm): the analytic
//    mask radius is r_e = sqrt(r^2 - c^2 / 4) (cone beam: sid r_e / sqrt(sad^2 - r_e^2) at the detector),
//    but at so thin a chord the partial-volume rim (0.5 mm voxels) counts too, so the oracle is a bracket:
//    r_e -/+ half a voxel diagonal (0.35 mm), and the measured value is printed;
//  - the cylinder shifted 3 mm across the beam: two discs of radius R a distance d = 3 M apart overlap in
//    the lens A = 2 R^2 acos(d / 2R) - (d / 2) sqrt(4 R^2 - d^2), so Dice = A / (pi R^2) and
//    IoU = A / (2 pi R^2 - A), within 0.01;
//  - a sequence against itself: Dice = IoU = 1 for every frame (exact);
//  - matching by time: nearest frames within half the shortest frame interval, one to one (exact).
#include "DRRTestSupport.h"

#include "cementsph/drr/AttenuationVolume.h"
#include "cementsph/drr/XraySequence.h"
#include "cementsph/drr/XraySequenceComparison.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <map>

using namespace cementsph;
using namespace cementsph::drrtest;
using drr::XraySequence;
using drr::XraySequenceOptions;
using cementsph::drrtest::Vec3;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kCementRadiusMm = 5.0, kCylinderLengthMm = 6.5; // its ends on voxel faces
constexpr double kTissueHU = 40.0, kCementExcessHU = 3000.0;
const double kCementExtraMuPerMm = drr::AttenuationVolume::kMuWaterPerMm * kCementExcessHU / 1000.0; // 0.066

enum class Cement { None, Ball, Cylinder };

// The cement's centre: off the voxel lattice across the beam, so that no voxel column is cut exactly in half
// (a column at exactly the half threshold would go either way by float rounding).
const Vec3 kCentre{0.0, 0.17, 0.23};

// 61^3 voxels of 0.5 mm centred on the origin: a soft-tissue ball (r 14 mm) and, optionally, cement: a ball
// of radius 5 mm, or a cylinder of radius 5 mm and length 6.5 mm along x (the beam at gantry 0). 5^3
// sub-samples per voxel: partial-volume fractions in steps of 1/25 across the beam, never exactly 1/2.
// Made once per (cement, centre): several tests project the same volumes.
vtkSmartPointer<vtkImageData> frameVolume(Cement cement, const Vec3& c = kCentre) {
  static std::map<std::pair<Cement, Vec3>, vtkSmartPointer<vtkImageData>> made;
  auto& volume = made[{cement, c}];
  if (volume) return volume;
  VolumeGrid grid = centredGrid({61, 61, 61}, {0.5, 0.5, 0.5}, {0, 0, 0});
  grid.subsamples = 5;
  volume = voxelise(grid, [=](const Vec3& p) {
    const double x = p[0] - c[0], y = p[1] - c[1], z = p[2] - c[2];
    const double r2 = kCementRadiusMm * kCementRadiusMm;
    if (cement == Cement::Ball && x * x + y * y + z * z <= r2) return kTissueHU + kCementExcessHU;
    if (cement == Cement::Cylinder && std::abs(x) <= 0.5 * kCylinderLengthMm && y * y + z * z <= r2)
      return kTissueHU + kCementExcessHU;
    return p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= 14.0 * 14.0 ? kTissueHU : -1000.0;
  });
  return volume;
}

// Half the cylinder's excess line integral, in mm of water: the unbiased threshold for its edge.
double halfCylinderWaterMm() {
  return 0.5 * kCylinderLengthMm * kCementExtraMuPerMm / drr::AttenuationVolume::kMuWaterPerMm; // 9.75 mm
}

XraySequenceOptions coneBeam(double thresholdWaterMm) {
  XraySequenceOptions o;
  o.geometry = detector(128, 48.0, false); // 0.375 mm pixels at the detector, 0.25 mm at the isocentre
  o.cementThresholdWaterMm = thresholdWaterMm;
  return o;
}

double lensArea(double r, double d) { return 2 * r * r * std::acos(d / (2 * r)) - 0.5 * d * std::sqrt(4 * r * r - d * d); }

} // namespace

TEST(XraySequence, ThresholdIsMillimetresOfWaterInDrrUnits) {
  const XraySequence s(coneBeam(2.5));
  EXPECT_DOUBLE_EQ(XraySequence::drrPerWaterMm(), 0.022 * 0.1);
  EXPECT_DOUBLE_EQ(s.thresholdDrr(), 2.5 * 0.0022);
}

TEST(XraySequence, ConeBeamCylinderAreaIsPiR2TimesMagnificationSquared) {
  const XraySequenceOptions o = coneBeam(halfCylinderWaterMm());
  XraySequence s(o);
  s.addFrame(0.0, frameVolume(Cement::None));
  s.addFrame(2.0, frameVolume(Cement::Cylinder));
  ASSERT_EQ(s.frames().size(), 2u);
  EXPECT_EQ(s.frames()[0].cementPixels, 0u); // the background has no cement by definition
  const double m = o.geometry.sidMm / o.geometry.sadMm;
  const double piR2 = kPi * kCementRadiusMm * kCementRadiusMm;
  const auto& f = s.frames()[1];
  std::cout << "cone beam, cylinder: " << f.cementPixels << " px, detector area " << f.detectorAreaMm2
            << " mm^2 (pi r^2 M^2 = " << piR2 * m * m << "), at the isocentre " << f.projectedAreaMm2
            << " mm^2 (pi r^2 = " << piR2 << ")\n";
  EXPECT_NEAR(f.detectorAreaMm2, piR2 * m * m, 0.015 * piR2 * m * m);
  EXPECT_NEAR(f.projectedAreaMm2, piR2, 0.015 * piR2);
  EXPECT_NEAR(f.projectedAreaMm2, f.detectorAreaMm2 / (m * m), 1e-9);
  // The mask is the disc about the cylinder's projection: its centroid lies within half a pixel of it.
  const auto centre = o.geometry.project(kCentre);
  double si = 0, sj = 0;
  const auto* mask = static_cast<const unsigned char*>(f.cementMask->GetScalarPointer());
  for (int j = 0; j < 128; ++j)
    for (int i = 0; i < 128; ++i)
      if (mask[j * 128 + i]) si += i, sj += j;
  EXPECT_NEAR(si / double(f.cementPixels), centre[0], 0.5);
  EXPECT_NEAR(sj / double(f.cementPixels), centre[1], 0.5);
}

TEST(XraySequence, ParallelBeamCylinderAreaIsPiR2) {
  XraySequenceOptions o;
  o.geometry = detector(128, 32.0, true); // 0.25 mm pixels, no magnification
  o.cementThresholdWaterMm = halfCylinderWaterMm();
  XraySequence s(o);
  s.addFrame(0.0, frameVolume(Cement::None));
  s.addFrame(1.0, frameVolume(Cement::Cylinder));
  const double piR2 = kPi * kCementRadiusMm * kCementRadiusMm;
  std::cout << "parallel beam, cylinder: " << s.frames()[1].projectedAreaMm2 << " mm^2 (pi r^2 = " << piR2 << ")\n";
  EXPECT_NEAR(s.frames()[1].projectedAreaMm2, piR2, 0.015 * piR2);
  EXPECT_DOUBLE_EQ(s.frames()[1].projectedAreaMm2, s.frames()[1].detectorAreaMm2);
}

TEST(XraySequence, ConeBeamBallAtTheDefaultThresholdIsWithinHalfAVoxelOfItsSilhouette) {
  const XraySequenceOptions o = coneBeam(1.0);
  XraySequence s(o);
  s.addFrame(0.0, frameVolume(Cement::None));
  s.addFrame(1.0, frameVolume(Cement::Ball));
  const double chord = o.cementThresholdWaterMm * drr::AttenuationVolume::kMuWaterPerMm / kCementExtraMuPerMm;
  const double re = std::sqrt(kCementRadiusMm * kCementRadiusMm - 0.25 * chord * chord);
  const double sad = o.geometry.sadMm, sid = o.geometry.sidMm, halfDiagonal = 0.5 * std::sqrt(0.5);
  auto isocentreArea = [&](double b) { // the silhouette of radius b at the detector, scaled back by (sad/sid)^2
    const double rd = sid * b / std::sqrt(sad * sad - b * b);
    return kPi * rd * rd * (sad / sid) * (sad / sid);
  };
  const double area = s.frames()[1].projectedAreaMm2;
  std::cout << "cone beam, ball, 1 mm of water: " << area << " mm^2 at the isocentre (analytic silhouette "
            << isocentreArea(re) << ", bracket " << isocentreArea(re - halfDiagonal) << " .. "
            << isocentreArea(re + halfDiagonal) << "; equivalent radius " << std::sqrt(area / kPi) << " mm)\n";
  EXPECT_GT(area, isocentreArea(re - halfDiagonal));
  EXPECT_LT(area, isocentreArea(re + halfDiagonal));
}

TEST(XraySequence, AgainstItselfDiceAndIoUAreOne) {
  XraySequence a(coneBeam(1.0)), b(coneBeam(1.0));
  for (XraySequence* s : {&a, &b}) {
    s->addFrame(0.0, frameVolume(Cement::None));
    s->addFrame(1.0, frameVolume(Cement::Ball, {0, 0.17, -2}));
    s->addFrame(2.0, frameVolume(Cement::Ball));
  }
  const auto c = drr::compareXraySequences(a, b);
  ASSERT_EQ(c.pairs.size(), 3u);
  EXPECT_EQ(c.matched(), 3u);
  EXPECT_DOUBLE_EQ(c.toleranceS, 0.5);
  for (const auto& p : c.pairs) {
    ASSERT_TRUE(p.dice && p.iou);
    EXPECT_EQ(*p.dice, 1.0);
    EXPECT_EQ(*p.iou, 1.0);
    EXPECT_EQ(*p.frame, *p.reference);
  }
}

TEST(XraySequence, ShiftedCementGivesTheLensOverlap) {
  const XraySequenceOptions o = coneBeam(halfCylinderWaterMm());
  XraySequence a(o), b(o);
  a.addFrame(0.0, frameVolume(Cement::None));
  a.addFrame(1.0, frameVolume(Cement::Cylinder));
  b.addFrame(0.0, frameVolume(Cement::None));
  // 3 mm along +y, the detector's u axis at gantry 0, in the plane of the isocentre: d = 3 sid / sad.
  b.addFrame(1.0, frameVolume(Cement::Cylinder, {0, kCentre[1] + 3, kCentre[2]}));
  const double m = o.geometry.sidMm / o.geometry.sadMm;
  const double r = kCementRadiusMm * m, d = 3.0 * m;
  const double lens = lensArea(r, d);
  const double dice = lens / (kPi * r * r), iou = lens / (2 * kPi * r * r - lens);
  const auto c = drr::compareXraySequences(a, b);
  ASSERT_EQ(c.pairs.size(), 2u);
  ASSERT_TRUE(c.pairs[1].dice.has_value());
  std::cout << "shifted 3 mm: Dice " << *c.pairs[1].dice << " (analytic " << dice << "), IoU " << *c.pairs[1].iou
            << " (analytic " << iou << ")\n";
  EXPECT_NEAR(*c.pairs[1].dice, dice, 0.01);
  EXPECT_NEAR(*c.pairs[1].iou, iou, 0.01);
  EXPECT_EQ(*c.pairs[0].dice, 1.0); // both backgrounds: empty masks
  // Same areas, as the shift is across the beam.
  EXPECT_NEAR(b.frames()[1].projectedAreaMm2, a.frames()[1].projectedAreaMm2, 0.01 * a.frames()[1].projectedAreaMm2);
}

TEST(XraySequence, FramesAreMatchedByTimeOneToOne) {
  XraySequenceOptions o;
  o.geometry = detector(8, 20.0, true);
  const auto v = voxelise(centredGrid({5, 5, 5}, {1, 1, 1}, {0, 0, 0}), balls({{{0, 0, 0}, 1.5, 500}}));
  XraySequence a(o), b(o);
  for (double t : {0.0, 1.0, 2.0}) a.addFrame(t, v);
  for (double t : {0.0, 2.05}) b.addFrame(t, v);
  auto c = drr::compareXraySequences(a, b); // tolerance: half of 1 s
  EXPECT_DOUBLE_EQ(c.toleranceS, 0.5);
  ASSERT_EQ(c.pairs.size(), 3u);
  EXPECT_EQ(*c.pairs[0].reference, 0u);
  EXPECT_FALSE(c.pairs[1].reference.has_value()); // t = 1 s: nothing within 0.5 s
  EXPECT_FALSE(c.pairs[1].dice.has_value());
  EXPECT_EQ(*c.pairs[2].reference, 1u);
  EXPECT_EQ(c.matched(), 2u);
  // A tolerance of 0: only exact instants; b's 2.05 s frame is then listed on its own, in time order.
  c = drr::compareXraySequences(a, b, 0.0);
  ASSERT_EQ(c.pairs.size(), 4u);
  EXPECT_EQ(c.matched(), 1u);
  EXPECT_DOUBLE_EQ(c.pairs[3].timeS, 2.05);
  EXPECT_FALSE(c.pairs[3].frame.has_value());
  // One to one: with a large tolerance b's frame at 2.05 s goes to a's 2 s frame (closest), not to 1 s.
  c = drr::compareXraySequences(a, b, 10.0);
  EXPECT_EQ(c.matched(), 2u);
  EXPECT_EQ(*c.pairs[2].reference, 1u);
  EXPECT_FALSE(c.pairs[1].reference.has_value());
  // Single frames only: any time difference matches.
  XraySequence one(o), other(o);
  one.addFrame(0.0, v);
  other.addFrame(7.0, v);
  EXPECT_TRUE(std::isinf(drr::defaultMatchToleranceS(one, other)));
  EXPECT_EQ(drr::compareXraySequences(one, other).matched(), 1u);
}

TEST(XraySequence, BadInputIsRefusedAndLeavesTheSequenceUnchanged) {
  XraySequenceOptions o;
  o.geometry = detector(8, 20.0, true);
  const auto v = voxelise(centredGrid({5, 5, 5}, {1, 1, 1}, {0, 0, 0}), balls({{{0, 0, 0}, 1.5, 500}}));
  XraySequence s(o);
  s.addFrame(1.0, v);
  EXPECT_THROW(s.addFrame(1.0, v), std::invalid_argument); // not after the previous frame
  EXPECT_THROW(s.addFrame(std::numeric_limits<double>::quiet_NaN(), v), std::invalid_argument);
  EXPECT_THROW(s.addFrame(2.0, nullptr), std::invalid_argument);
  vtkNew<vtkImageData> empty;
  EXPECT_THROW(s.addFrame(2.0, empty), std::invalid_argument);
  EXPECT_EQ(s.frames().size(), 1u);
  o.cementThresholdWaterMm = 0.0;
  EXPECT_THROW(XraySequence{o}, std::invalid_argument);
  o.cementThresholdWaterMm = 1.0;
  o.geometry.sidMm = 500; // closer than the source-axis distance
  o.geometry.parallel = false;
  EXPECT_THROW(XraySequence{o}, std::invalid_argument);
  XraySequenceOptions other;
  other.geometry = detector(16, 20.0, true);
  XraySequence t(other);
  t.addFrame(1.0, v);
  EXPECT_THROW(drr::compareXraySequences(s, t), std::invalid_argument); // different detectors
  EXPECT_THROW(drr::compareXraySequences(s, s, -1.0), std::invalid_argument);
}

TEST(DRRGeometry, FitDetectorToABoxPutsItsExtremeCornerAtTheMargin) {
  drr::DRRGeometry g = detector(100, 400.0, false, {1, 2, 3});
  g.cols = 120;
  g.gantryAngleDeg = 30;
  const std::array<double, 6> box{-10, 14, -6, 20, -3, 11};
  g.fitDetectorTo(box, 1.25);
  EXPECT_NEAR(g.pixelWidthMm(), g.pixelHeightMm(), 1e-12); // square pixels
  // Every corner lands on the detector, and the farthest one (in the limiting direction) at 1/1.25 of
  // the half-width from the centre.
  double worstU = 0, worstV = 0;
  for (int c = 0; c < 8; ++c) {
    const auto ij = g.project({box[(c & 1) ? 1 : 0], box[(c & 2) ? 3 : 2], box[(c & 4) ? 5 : 4]});
    worstU = std::max(worstU, std::abs(ij[0] - 0.5 * (g.cols - 1)) / (0.5 * g.cols));
    worstV = std::max(worstV, std::abs(ij[1] - 0.5 * (g.rows - 1)) / (0.5 * g.rows));
  }
  EXPECT_NEAR(std::max(worstU, worstV), 1.0 / 1.25, 1e-9);
  EXPECT_LE(std::min(worstU, worstV), 1.0 / 1.25 + 1e-9);
  EXPECT_THROW(g.fitDetectorTo(box, 0.9), std::invalid_argument);
  EXPECT_THROW(g.fitDetectorTo({0, -1, 0, 1, 0, 1}), std::invalid_argument);
  EXPECT_THROW(g.fitDetectorTo({0, 2000, 0, 1, 0, 1}), std::invalid_argument); // reaches behind the source
}
