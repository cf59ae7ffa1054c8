// The anatomy module (issue 20, items 1 and 7) on the vertebra phantom's anatomy variant: marrow fat inside the
// body, discs above and below, a basivertebral vein. The oracle is the variant's analytic geometry, written out
// here from the phantom's documented layout (VertebraPhantom.h: the body's centre at (field_x / 2, 15 + 6,
// field_z / 2), semi-axes 20 x 15 mm, half height 12.5 mm; fat 7 mm left, 3 mm anterior, 2 mm superior of it;
// the vein from centre + (-4, 2, -5) to centre + (-22, 20, -5); the canal (radius 8 mm) 23 mm behind the centre,
// 10 mm either side of it in height), never from the anatomy code. Partial volume: a voxel counts as "inside" a
// shape when its whole box is (the phantom averages 3^3 sub-samples per voxel), so the boundary shell of one voxel
// is left out where the test says so.
#include "cementsph/anatomy/LeakSites.h"
#include "cementsph/anatomy/VertebraAnatomy.h"
#include "cementsph/phantom/VertebraPhantom.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace {
using namespace cementsph;
using anatomy::TissueClass;
using P = std::array<double, 3>;

constexpr double kA = 20, kB = 15, kH = 12.5, kCanalR = 8, kFatR = 5, kDiscH = 10, kVeinR = 2;

phantom::VertebraOptions variantOptions() {
  phantom::VertebraOptions o;
  o.fieldMm = {64, 70, 57}; // room for both discs (10 mm) and the neighbours' end plates
  o.marrowFatRadiusMm = kFatR;
  o.marrowFatHu = -30;
  o.discHeightMm = kDiscH;
  o.discHu = 80;
  o.veinRadiusMm = kVeinR;
  o.veinHu = 60;
  return o;
}

// The analytic geometry of the variant (see the header comment).
struct Truth {
  P c, fat, veinA, veinB, canal;
  double upper[2], lower[2];
  explicit Truth(const phantom::VertebraOptions& o) {
    c = {o.fieldMm[0] / 2, kB + 6, o.fieldMm[2] / 2};
    fat = {c[0] + 7, c[1] - 3, c[2] + 2};
    veinA = {c[0] - 4, c[1] + 2, c[2] - 5};
    veinB = {c[0] - 22, c[1] + 20, c[2] - 5};
    canal = {c[0], c[1] + kB + kCanalR, c[2]};
    upper[0] = c[2] + kH;
    upper[1] = c[2] + kH + kDiscH;
    lower[0] = c[2] - kH - kDiscH;
    lower[1] = c[2] - kH;
  }
  double radial(const P& p) const { return std::hypot((p[0] - c[0]) / kA, (p[1] - c[1]) / kB); }
  // The shapes (a point inside; count() asks it of all 8 corners of a voxel's box).
  bool inBody(const P& p) const { return radial(p) <= 1 && std::abs(p[2] - c[2]) <= kH; }
  bool inFat(const P& p) const { return std::hypot(p[0] - fat[0], p[1] - fat[1], p[2] - fat[2]) <= kFatR; }
  bool inDisc(const P& p) const {
    return radial(p) <= 1 && ((p[2] >= upper[0] && p[2] <= upper[1]) || (p[2] >= lower[0] && p[2] <= lower[1]));
  }
  bool inCanal(const P& p) const {
    return std::hypot(p[0] - canal[0], p[1] - canal[1]) <= kCanalR && std::abs(p[2] - c[2]) <= 0.8 * kH && radial(p) > 1;
  }
  // The openings of the posterior wall, 1 mm around each: the 3 mm foramen and the vein's channel.
  bool inForamen(const P& p) const { return p[1] > c[1] && std::hypot(p[0] - c[0], p[2] - c[2]) <= 1.5 + 1; }
  bool inVeinChannel(const P& p) const { return veinDistance(p) <= kVeinR + 1 && radial(p) > 0.8; }
  // The vein outside the body, 2 mm clear of its wall (the wall's partial-volume rim is the vertebra's), to 0.25 mm
  // of partial volume.
  bool inVeinOutside(const P& p) const { return veinDistance(p) <= kVeinR + 0.25 && radial(p) >= 1 + 2.0 / kB; }
  double veinDistance(const P& p) const {
    P u, q;
    double uu = 0, t = 0;
    for (int a = 0; a < 3; ++a) {
      u[a] = veinB[a] - veinA[a];
      q[a] = p[a] - veinA[a];
      uu += u[a] * u[a];
      t += q[a] * u[a];
    }
    t = std::clamp(t / uu, 0.0, 1.0);
    double d = 0;
    for (int a = 0; a < 3; ++a) d += (q[a] - t * u[a]) * (q[a] - t * u[a]);
    return std::sqrt(d);
  }
};

struct Scene {
  phantom::VertebraOptions options;
  phantom::VertebraResult phantom;
  anatomy::Grid grid;
  std::vector<float> hu;
  std::unique_ptr<Truth> truth;
  anatomy::AnatomyOptions ao; // soft_tissue_max_hu 40, cortical_hu 350: BoneCalibration's defaults
  explicit Scene(const phantom::VertebraOptions& o = variantOptions()) : options(o) {
    phantom = phantom::makeVertebra(options);
    truth = std::make_unique<Truth>(options);
    const auto size = phantom.ct->GetLargestPossibleRegion().GetSize();
    for (int a = 0; a < 3; ++a) {
      grid.size[a] = int(size[a]);
      grid.spacingMm[a] = phantom.ct->GetSpacing()[a];
      grid.originMm[a] = phantom.ct->GetOrigin()[a];
    }
    hu.assign(phantom.ct->GetBufferPointer(), phantom.ct->GetBufferPointer() + grid.count());
  }
  P centre(int i, int j, int k) const { return grid.centreMm(i, j, k); }
  // Visit every voxel with its centre and the 8 corners of its box.
  void forEach(const std::function<void(std::size_t, const P&, const std::array<P, 8>&)>& f) const {
    std::size_t n = 0;
    for (int k = 0; k < grid.size[2]; ++k)
      for (int j = 0; j < grid.size[1]; ++j)
        for (int i = 0; i < grid.size[0]; ++i, ++n) {
          const P p = centre(i, j, k);
          std::array<P, 8> corners;
          for (int q = 0; q < 8; ++q)
            for (int a = 0; a < 3; ++a) corners[q][a] = p[a] + ((q >> a) & 1 ? 0.5 : -0.5) * grid.spacingMm[a];
          f(n, p, corners);
        }
  }
};

const Scene& scene() {
  static const Scene s;
  return s;
}
const anatomy::Anatomy& ctAnatomy() {
  static const anatomy::Anatomy a =
      anatomy::classifyAnatomyFromCT(scene().hu.data(), scene().grid, scene().truth->c, scene().ao);
  return a;
}

bool allCorners(const std::array<P, 8>& cs, const std::function<bool(const P&)>& in) {
  for (const auto& c : cs)
    if (!in(c)) return false;
  return true;
}

// The voxels wholly inside a region, and how many of them carry the expected class.
struct Count {
  std::size_t inside = 0, right = 0;
  double share() const { return inside ? double(right) / double(inside) : 0.0; }
};
Count count(const Scene& s, const anatomy::Anatomy& a, const std::function<bool(const P&)>& in, TissueClass expected) {
  Count c;
  s.forEach([&](std::size_t n, const P&, const std::array<P, 8>& cs) {
    if (!allCorners(cs, in)) return;
    ++c.inside;
    if (a.at(n) == expected) ++c.right;
  });
  return c;
}
Count count(const anatomy::Anatomy& a, const std::function<bool(const P&)>& in, TissueClass expected) {
  return count(scene(), a, in, expected);
}
} // namespace

// The variant's geometry as the phantom reports it is the layout written out above (the oracle is the layout).
TEST(VertebraAnatomy, TheVariantReportsItsDocumentedGeometry) {
  const auto& s = scene();
  const auto& t = *s.truth;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(s.phantom.bodyCentreMm[a], t.c[a], 1e-12);
    EXPECT_NEAR(s.phantom.marrowFatCentreMm[a], t.fat[a], 1e-12);
    EXPECT_NEAR(s.phantom.veinStartMm[a], t.veinA[a], 1e-12);
    EXPECT_NEAR(s.phantom.veinEndMm[a], t.veinB[a], 1e-12);
  }
  EXPECT_NEAR(s.phantom.upperDiscZMm[0], t.upper[0], 1e-12);
  EXPECT_NEAR(s.phantom.lowerDiscZMm[1], t.lower[1], 1e-12);
  const auto j = s.phantom.toJson();
  EXPECT_TRUE(j.contains("marrow_fat") && j.contains("discs") && j.contains("vein"));
  // The fat is below the bone band (its centre voxel: -30 HU +- 5 sigma of the 10 HU noise).
  const auto ci = s.grid.continuousIndex(t.fat);
  const std::size_t n = std::size_t(std::lround(ci[0])) +
                        std::size_t(s.grid.size[0]) * (std::size_t(std::lround(ci[1])) + std::size_t(s.grid.size[1]) * std::size_t(std::lround(ci[2])));
  EXPECT_LT(s.hu[n], 40.0f);
  EXPECT_NEAR(s.hu[n], -30.0, 50.0);
}

// The default phantom has none of the variant's keys (its truth.json is unchanged).
TEST(VertebraAnatomy, TheDefaultPhantomHasNoVariantKeys) {
  const auto j = phantom::VertebraResult{}.toJson();
  EXPECT_FALSE(j.contains("marrow_fat") || j.contains("discs") || j.contains("vein"));
}

// (a) Marrow fat enclosed by trabecular bone is the target vertebra: every voxel that touches the fat sphere
// (its box within 5 mm of the centre), exactly none left out.
TEST(VertebraAnatomy, MarrowFatInsideTheBodyIsTheTargetNotALeak) {
  const auto& s = scene();
  const auto& a = ctAnatomy();
  EXPECT_EQ(a.rule, "ct-bone-rule");
  EXPECT_TRUE(a.targetFound) << a.description;
  std::size_t touching = 0, wrong = 0;
  s.forEach([&](std::size_t n, const P& p, const std::array<P, 8>&) {
    double d2 = 0; // distance from the fat's centre to the voxel's box
    for (int q = 0; q < 3; ++q) {
      const double h = 0.5 * s.grid.spacingMm[q], e = std::max(0.0, std::abs(p[q] - s.truth->fat[q]) - h);
      d2 += e * e;
    }
    if (std::sqrt(d2) > kFatR) return;
    ++touching;
    if (a.at(n) != TissueClass::TargetVertebra) ++wrong;
  });
  EXPECT_GT(touching, 300u); // 4/3 pi 5^3 / 1.5 mm^3 = 349 voxels wholly inside, more touching
  EXPECT_EQ(wrong, 0u);
}

// The whole body is the target vertebra: every voxel wholly inside the elliptic cylinder (cortex, trabecular
// bone, fat, the vein inside) is, exactly, except the openings of the posterior wall (the 3 mm foramen and the
// vein's channel, 1 mm around each, where the wall is open to the canal and the soft tissue).
TEST(VertebraAnatomy, TheWholeBodyIsTheTarget) {
  const auto& s = scene();
  const auto& t = *s.truth;
  const Count c = count(ctAnatomy(), [&](const P& p) { return t.inBody(p) && !t.inForamen(p) && !t.inVeinChannel(p); },
                        TissueClass::TargetVertebra);
  EXPECT_GT(c.inside, 12000u); // pi 20 15 25 / 1.5 mm^3 = 15700 voxels less the boundary shell (~20 %)
  EXPECT_EQ(c.right, c.inside);
}

// The default phantom (the bundled Data/vertebra-phantom's layout: no fat, no discs, no vein): the body is the
// target, exactly, but for the foramen; the canal is canal (>= 95 %); nothing is disc (no end plate has a
// neighbour within 15 mm); the bundled plan's tip is accepted.
TEST(VertebraAnatomy, TheDefaultPhantomUnderTheBoneRule) {
  const Scene sc{phantom::VertebraOptions{}};
  const auto& t = *sc.truth;
  const auto a = anatomy::classifyAnatomyFromCT(sc.hu.data(), sc.grid, sc.phantom.suggestedTipMm, sc.ao);
  EXPECT_EQ(anatomy::requireTipInVertebra(a, sc.hu.data(), sc.phantom.suggestedTipMm, false), TissueClass::TargetVertebra);
  const Count body = count(sc, a, [&](const P& c) { return t.inBody(c) && !t.inForamen(c); }, TissueClass::TargetVertebra);
  EXPECT_GT(body.inside, 12000u);
  EXPECT_EQ(body.right, body.inside);
  const Count canal = count(sc, a, [&](const P& c) { return t.inCanal(c); }, TissueClass::Canal);
  EXPECT_GT(canal.inside, 1500u);
  EXPECT_GE(canal.share(), 0.95) << canal.right << " of " << canal.inside;
  EXPECT_EQ(a.volumeMl(TissueClass::Disc), 0.0);
}

// A permutation and a flip of the grid's axes (the CT stored z-fastest and right-to-left, its direction saying
// so) give the same class in every voxel: the rule follows the patient's axes, not the array's.
TEST(VertebraAnatomy, APermutedFlippedGridGivesTheSameClasses) {
  const auto& s = scene();
  const int nx = s.grid.size[0], ny = s.grid.size[1], nz = s.grid.size[2];
  anatomy::Grid g; // index axes (z, -x, y): column 0 is patient z, 1 is -x, 2 is y
  g.size = {nz, nx, ny};
  g.spacingMm = {s.grid.spacingMm[2], s.grid.spacingMm[0], s.grid.spacingMm[1]};
  g.originMm = s.grid.centreMm(nx - 1, 0, 0);
  g.direction = {0, -1, 0, 0, 0, 1, 1, 0, 0};
  std::vector<float> hu(s.hu.size());
  auto old = [&](int i, int j, int k) { return std::size_t(i) + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * std::size_t(k)); };
  auto neu = [&](int i, int j, int k) {
    return std::size_t(k) + std::size_t(nz) * (std::size_t(nx - 1 - i) + std::size_t(nx) * std::size_t(j));
  };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) hu[neu(i, j, k)] = s.hu[old(i, j, k)];
  // The same voxel, the same place.
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(g.centreMm(4, 5, 6)[a], s.grid.centreMm(nx - 1 - 5, 6, 4)[a], 1e-12);
  const auto a = anatomy::classifyAnatomyFromCT(hu.data(), g, s.truth->c, s.ao);
  std::size_t differ = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) differ += a.at(neu(i, j, k)) != ctAnatomy().at(old(i, j, k)) ? 1 : 0;
  EXPECT_EQ(differ, 0u);
}

// Air around the scan changes nothing (what an oblique CT's aligned grid adds in its corners, AxisAlignedCT.h):
// the variant padded with air (-1000 HU) by 3 to 9 voxels, unevenly on the six sides, gives in every voxel of
// the original the class the unpadded variant gives (the oracle: the rule on the unpadded grid, whose field is
// soft tissue to its edges), and air in the padding; the target's centroid is the same point (to round-off of
// the shifted origin) and the description is the same line.
TEST(VertebraAnatomy, AirAroundTheScanChangesNoClass) {
  const auto& s = scene();
  const int nx = s.grid.size[0], ny = s.grid.size[1], nz = s.grid.size[2];
  const int before[3] = {3, 9, 4}, after[3] = {7, 5, 6};
  anatomy::Grid g = s.grid;
  for (int a = 0; a < 3; ++a) g.size[a] = s.grid.size[a] + before[a] + after[a];
  g.originMm = s.grid.centreMm(-before[0], -before[1], -before[2]);
  auto padded = [&](int i, int j, int k) {
    return std::size_t(i + before[0]) +
           std::size_t(g.size[0]) * (std::size_t(j + before[1]) + std::size_t(g.size[1]) * std::size_t(k + before[2]));
  };
  std::vector<float> hu(g.count(), -1000.0f);
  std::size_t n = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) hu[padded(i, j, k)] = s.hu[n++];
  const auto a = anatomy::classifyAnatomyFromCT(hu.data(), g, s.truth->c, s.ao);
  const auto& unpadded = ctAnatomy();
  std::size_t differ = 0;
  n = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) differ += a.at(padded(i, j, k)) != unpadded.at(n++) ? 1 : 0;
  EXPECT_EQ(differ, 0u);
  const std::size_t paddingVoxels = g.count() - s.grid.count();
  EXPECT_NEAR(a.volumeMl(TissueClass::Air), double(paddingVoxels) * g.voxelVolumeMm3() / 1000.0 + unpadded.volumeMl(TissueClass::Air),
              1e-9);
  EXPECT_TRUE(a.targetFound);
  for (int q = 0; q < 3; ++q) EXPECT_NEAR(a.targetCentroidMm[q], unpadded.targetCentroidMm[q], 1e-9);
  EXPECT_EQ(a.description, unpadded.description);
}

// Marrow fat open to a gap of the cortex is still bone: on a copy of the CT, fat (-30 HU) in a 4 mm ball whose
// posterior pole reaches the basivertebral foramen (centre 11 mm behind the body's centre, at mid height; written
// into every voxel of the ball that is not cortex, > 350 HU). In 3-D the fat reaches the canal through the
// foramen; the sagittal and coronal slices close it. Every voxel wholly inside the ball is the target.
TEST(VertebraAnatomy, MarrowFatAgainstTheForamenIsStillBone) {
  const auto& s = scene();
  const auto& t = *s.truth;
  const P f{t.c[0], t.c[1] + 11, t.c[2]};
  auto inBall = [&](const P& p) { return std::hypot(p[0] - f[0], p[1] - f[1], p[2] - f[2]) <= 4; };
  std::vector<float> hu = s.hu;
  s.forEach([&](std::size_t n, const P& p, const std::array<P, 8>&) {
    if (inBall(p) && hu[n] <= 350 && p[1] < t.c[1] + kB - 0.5) hu[n] = -30;
  });
  const auto a = anatomy::classifyAnatomyFromCT(hu.data(), s.grid, t.c, s.ao);
  const Count c = count(a, inBall, TissueClass::TargetVertebra);
  EXPECT_GT(c.inside, 60u); // 4/3 pi 4^3 / 1.5 mm^3 = 179 voxels less the shell
  EXPECT_EQ(c.right, c.inside);
}

// (b) The disc spaces are disc: >= 95 % of the voxels wholly inside each analytic disc (the body's elliptic
// section between the end plates; the shell of partial volume against the end plates and the edge left out).
TEST(VertebraAnatomy, TheDiscSpacesAreDisc) {
  const auto& t = *scene().truth;
  for (const double* z : {t.upper, t.lower}) {
    const Count c = count(ctAnatomy(), [&](const P& p) { return t.radial(p) <= 1 && p[2] >= z[0] && p[2] <= z[1]; },
                          TissueClass::Disc);
    EXPECT_GT(c.inside, 1500u); // pi 20 15 (10 - 1.5) / 1.5 mm^3 = 5340 voxels less the edge
    EXPECT_GE(c.share(), 0.95) << c.right << " of " << c.inside << " at z " << z[0];
  }
}

// (c) The canal (radius 8 mm, 10 mm either side of the body's mid height) is canal: >= 95 % of the voxels
// wholly inside it and wholly behind the body's ellipse.
TEST(VertebraAnatomy, TheCanalIsCanal) {
  const auto& t = *scene().truth;
  const Count c = count(ctAnatomy(), [&](const P& p) { return t.inCanal(p); }, TissueClass::Canal);
  EXPECT_GT(c.inside, 1500u); // pi 8^2 x 20 / 1.5 mm^3 = 2680 voxels less the shell
  EXPECT_GE(c.share(), 0.95) << c.right << " of " << c.inside;
}

// (d) The vein outside the body is vessel: >= 95 % of the voxels whose box lies within the tube (to 0.25 mm of
// partial volume) and 2 mm clear of the body's wall (the wall's partial-volume rim is the vertebra's). A voxel
// of 60 HU falls below the 40 HU band with the 10 HU noise 2.3 % of the time; the rule fills such holes.
TEST(VertebraAnatomy, TheVeinOutsideTheBodyIsVessel) {
  const auto& t = *scene().truth;
  const Count c = count(ctAnatomy(), [&](const P& p) { return t.inVeinOutside(p); }, TissueClass::Vessel);
  EXPECT_GT(c.inside, 10u);
  EXPECT_GE(c.share(), 0.95) << c.right << " of " << c.inside;
  std::printf("vein outside the body: %zu of %zu voxels vessel\n", c.right, c.inside);
  // And the vein inside the body (bone-band HU, enclosed by the cortex) is the vertebra's.
  const Count inside = count(ctAnatomy(), [&](const P& p) { return t.veinDistance(p) <= kVeinR && t.radial(p) <= 0.7; },
                             TissueClass::TargetVertebra);
  EXPECT_GT(inside.inside, 5u);
  EXPECT_EQ(inside.right, inside.inside);
}

// The vessel rule's two arms and its limit, on a copy of the CT with two tubes along z written into the soft
// tissue (20 mm long, mid height): a contrast-filled one (200 HU, radius 4 mm, 5 mm clear of the body,
// anterior-left like an aorta) is vessel; a thick one of muscle HU (55 HU, radius 6 mm, against the body's right
// side wall) is not (thicker than max_vein_radius_mm 3): >= 95 % of the voxels wholly inside each.
TEST(VertebraAnatomy, ContrastTubesAreVesselsThickMuscleIsNot) {
  const auto& s = scene();
  const auto& t = *s.truth;
  const P aorta{t.c[0] + 26, t.c[1] - 8, 0}, muscle{t.c[0] - 25, t.c[1] - 4, 0};
  auto inTube = [&](const P& p, const P& axis, double r) {
    return std::hypot(p[0] - axis[0], p[1] - axis[1]) <= r && std::abs(p[2] - t.c[2]) <= 10;
  };
  std::vector<float> hu = s.hu;
  s.forEach([&](std::size_t n, const P& p, const std::array<P, 8>&) {
    if (inTube(p, aorta, 4)) hu[n] = 200 + (hu[n] - 20); // the same noise about the new mean
    if (inTube(p, muscle, 6) && t.radial(p) > 1) hu[n] = 55 + (hu[n] - 20);
  });
  const auto a = anatomy::classifyAnatomyFromCT(hu.data(), s.grid, t.c, s.ao);
  const Count enhanced = count(a, [&](const P& p) { return inTube(p, aorta, 4); }, TissueClass::Vessel);
  EXPECT_GT(enhanced.inside, 400u); // pi 4^2 20 / 1.5 mm^3 = 670 voxels less the shell (~30 %)
  EXPECT_GE(enhanced.share(), 0.95) << enhanced.right << " of " << enhanced.inside;
  const Count thick = count(a, [&](const P& p) { return inTube(p, muscle, 6) && t.radial(p) > 1 + 2.0 / kB; },
                            TissueClass::OtherSoftTissue);
  EXPECT_GT(thick.inside, 700u); // the part of the 6 mm tube 2 mm clear of the body
  EXPECT_GE(thick.share(), 0.95) << thick.right << " of " << thick.inside;
}

// At the clinical scan (0.98 mm pixels, 2 mm slices) with twice the noise (20 HU): a 1 mm end plate
// averaged over a 2 mm slice shows about 320 HU, below cortical_hu; the shell (wall_hu 250) still bounds the
// body. The same oracles: the body (but for the openings) and the fat wholly target; >= 95 % of the discs and the
// canal; >= 90 % of the vein outside the body (at 20 HU noise a 60 HU voxel falls below 40 HU 16 % of the time
// and only the holes that 4 vessel neighbours surround are filled).
TEST(VertebraAnatomy, AtClinicalSliceThicknessAndNoise) {
  auto o = variantOptions();
  o.spacingMm = {0.98, 0.98, 2.0};
  o.noiseHu = 20;
  o.fieldMm = {64, 70, 60};
  const Scene sc(o);
  const auto& t = *sc.truth;
  const auto a = anatomy::classifyAnatomyFromCT(sc.hu.data(), sc.grid, t.c, sc.ao);
  const Count body = count(sc, a, [&](const P& c) { return t.inBody(c) && !t.inForamen(c) && !t.inVeinChannel(c); },
                           TissueClass::TargetVertebra);
  const Count fat = count(sc, a, [&](const P& c) { return t.inFat(c); }, TissueClass::TargetVertebra);
  const Count disc = count(sc, a, [&](const P& c) { return t.inDisc(c); }, TissueClass::Disc);
  const Count canal = count(sc, a, [&](const P& c) { return t.inCanal(c); }, TissueClass::Canal);
  const Count vein = count(sc, a, [&](const P& c) { return t.inVeinOutside(c); }, TissueClass::Vessel);
  std::printf("2 mm slices, 20 HU noise: body %zu/%zu, fat %zu/%zu, discs %zu/%zu, canal %zu/%zu, vein %zu/%zu\n",
              body.right, body.inside, fat.right, fat.inside, disc.right, disc.inside, canal.right, canal.inside,
              vein.right, vein.inside);
  EXPECT_GT(body.inside, 8000u) << a.description; // pi 20 15 25 / 1.92 mm^3 = 12300 less the shell
  EXPECT_EQ(body.right, body.inside);
  EXPECT_GT(fat.inside, 80u);
  EXPECT_EQ(fat.right, fat.inside);
  EXPECT_GT(disc.inside, 5000u);
  EXPECT_GE(disc.share(), 0.95) << disc.right << " of " << disc.inside;
  EXPECT_GT(canal.inside, 1000u);
  EXPECT_GE(canal.share(), 0.95) << canal.right << " of " << canal.inside;
  EXPECT_GT(vein.inside, 10u);
  EXPECT_GE(vein.share(), 0.90) << vein.right << " of " << vein.inside;
}

// (e) A tip outside the target's bone (disc, canal, the vein outside the body, a fat pocket, an air pocket) is
// refused with one line naming the tissue; the body's centre and a point in the enclosed marrow fat are accepted.
TEST(VertebraAnatomy, TipsOutsideBoneAreRefusedByTissue) {
  const auto& s = scene();
  const auto& t = *s.truth;
  EXPECT_EQ(anatomy::requireTipInVertebra(ctAnatomy(), s.hu.data(), t.c, false), TissueClass::TargetVertebra);
  EXPECT_EQ(anatomy::requireTipInVertebra(ctAnatomy(), s.hu.data(), t.fat, false), TissueClass::TargetVertebra);
  // The same rule run from a tip in the fat finds the same vertebra (the tip's own voxel is below the band).
  const auto fromFat = anatomy::classifyAnatomyFromCT(s.hu.data(), s.grid, t.fat, s.ao);
  EXPECT_EQ(anatomy::tissueAtTip(fromFat, t.fat), TissueClass::TargetVertebra);

  // A copy of the CT with a fat pocket (-100 HU) and an air pocket (-1000 HU), 6 mm cubes, lateral to the body.
  std::vector<float> hu = s.hu;
  const P fatOut{t.c[0] + 26, t.c[1], t.c[2]}, airOut{t.c[0] - 26, t.c[1], t.c[2]};
  s.forEach([&](std::size_t n, const P& p, const std::array<P, 8>&) {
    auto near = [&](const P& q) { return std::abs(p[0] - q[0]) <= 3 && std::abs(p[1] - q[1]) <= 3 && std::abs(p[2] - q[2]) <= 3; };
    if (near(fatOut)) hu[n] = -100;
    if (near(airOut)) hu[n] = -1000;
  });
  struct Case {
    P tip;
    TissueClass expected;
    const char* words;
  };
  const P discTip{t.c[0], t.c[1], 0.5 * (t.upper[0] + t.upper[1])};
  // On the vein's axis 80 % of the way out: outside the body, clear of its wall's rim (Truth::inVeinOutside).
  P veinTip;
  for (int q = 0; q < 3; ++q) veinTip[q] = t.veinA[q] + 0.8 * (t.veinB[q] - t.veinA[q]);
  ASSERT_TRUE(t.inVeinOutside(veinTip));
  for (const Case& k : {Case{discTip, TissueClass::Disc, "intervertebral disc"},
                        Case{t.canal, TissueClass::Canal, "spinal canal"},
                        Case{veinTip, TissueClass::Vessel, "blood vessel"},
                        Case{fatOut, TissueClass::OtherSoftTissue, "soft tissue"},
                        Case{airOut, TissueClass::Air, "air"}}) {
    const auto a = anatomy::classifyAnatomyFromCT(hu.data(), s.grid, k.tip, s.ao);
    EXPECT_TRUE(a.targetFound) << a.description; // every tip is within 20 mm of the body's core
    EXPECT_EQ(anatomy::tissueAtTip(a, k.tip), k.expected) << k.words;
    try {
      anatomy::requireTipInVertebra(a, hu.data(), k.tip, false);
      ADD_FAILURE() << "a tip in " << k.words << " was accepted";
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(k.words), std::string::npos) << m;
      EXPECT_NE(m.find("allow_tip_outside_bone"), std::string::npos) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
    EXPECT_EQ(anatomy::requireTipInVertebra(a, hu.data(), k.tip, true), k.expected); // deliberate: allowed
  }
}

namespace {
// A ball of cement: per voxel the share of its box inside the ball (5^3 sub-samples), fill 1 there; arrival at
// 10 s + 1 s per mm from the centre.
void ball(const P& centre, double radius, std::vector<double>& fill, std::vector<double>& arrival) {
  const auto& s = scene();
  fill.assign(s.grid.count(), 0.0);
  arrival.assign(s.grid.count(), -1.0);
  s.forEach([&](std::size_t n, const P& p, const std::array<P, 8>&) {
    const double d = std::hypot(p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]);
    if (d > radius + 2) return;
    int in = 0;
    for (int c = 0; c < 5; ++c)
      for (int b = 0; b < 5; ++b)
        for (int a = 0; a < 5; ++a) {
          const double x = p[0] + ((a + 0.5) / 5 - 0.5) * s.grid.spacingMm[0], y = p[1] + ((b + 0.5) / 5 - 0.5) * s.grid.spacingMm[1],
                       z = p[2] + ((c + 0.5) / 5 - 0.5) * s.grid.spacingMm[2];
          if (std::hypot(x - centre[0], y - centre[1], z - centre[2]) <= radius) ++in;
        }
    fill[n] = in / 125.0;
    if (in > 0) arrival[n] = 10.0 + d;
  });
}
} // namespace

// (f) A 3 mm ball of cement in the upper disc is one disc site of the ball's volume (4/3 pi 3^3 = 0.1131 ml,
// within 5 %), at the ball's centre (within 0.5 mm), first reached at 10 s (+ the nearest voxel's distance,
// under 1 mm); a 7 mm ball about the marrow fat leaks nothing and is held inside (its volume within 5 %).
TEST(VertebraAnatomy, LeakSitesByClassWithTheirVolume) {
  const auto& t = *scene().truth;
  const double pi = std::acos(-1.0);
  std::vector<double> fill, arrival;
  const P inDisc{t.c[0], t.c[1], 0.5 * (t.upper[0] + t.upper[1])};
  ball(inDisc, 3.0, fill, arrival);
  const auto r = anatomy::classifyLeaks(ctAnatomy(), fill, arrival, {});
  const double v = 4.0 / 3.0 * pi * 27 / 1000;
  ASSERT_EQ(r.sites.size(), 1u) << r.toJson().dump();
  EXPECT_EQ(r.sites[0].kind, "disc");
  EXPECT_NEAR(r.sites[0].volumeMl, v, 0.05 * v);
  EXPECT_NEAR(r.volumeMlByKind.at("disc"), v, 0.05 * v);
  EXPECT_NEAR(r.leakedMl, v, 0.05 * v);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(r.sites[0].positionMm[a], inDisc[a], 0.5);
  EXPECT_GE(r.sites[0].firstTimeS, 10.0);
  EXPECT_LT(r.sites[0].firstTimeS, 11.0);
  EXPECT_TRUE(r.toJson().at("sites")[0].contains("first_time_s"));

  ball(t.fat, 7.0, fill, arrival);
  const auto inside = anatomy::classifyLeaks(ctAnatomy(), fill, arrival, {});
  const double w = 4.0 / 3.0 * pi * 343 / 1000;
  EXPECT_EQ(inside.leakedMl, 0.0) << inside.toJson().dump();
  EXPECT_TRUE(inside.sites.empty());
  EXPECT_NEAR(inside.insideMl, w, 0.05 * w);

  // Porosity scales the cement a voxel holds: half porosity, half the volume (exactly, in floating point).
  ball(inDisc, 3.0, fill, arrival);
  const auto half = anatomy::classifyLeaks(ctAnatomy(), fill, arrival, std::vector<double>(fill.size(), 0.5));
  EXPECT_NEAR(half.leakedMl, 0.5 * r.leakedMl, 1e-12);
  EXPECT_THROW(anatomy::classifyLeaks(ctAnatomy(), std::vector<double>(3, 0.0), {}, {}), std::invalid_argument);
}

// (g) Cement in the basivertebral vein outside the body (every voxel wholly inside the vein's outer segment, 2 mm
// clear of the wall: Truth::inVeinOutside, from the phantom's layout) is leakage of its whole volume (exactly: none
// of it is the target), reported as venous: the largest site is venous and holds at least 90 % of it (the rest:
// the vein's partial-volume edge, classed soft tissue, a cortex_breach site).
TEST(VertebraAnatomy, CementInTheVeinIsAVenousLeak) {
  const auto& s = scene();
  const auto& t = *s.truth;
  std::vector<double> fill(s.grid.count(), 0.0);
  std::size_t voxels = 0;
  s.forEach([&](std::size_t n, const P&, const std::array<P, 8>& cs) {
    if (!allCorners(cs, [&](const P& c) { return t.inVeinOutside(c); })) return;
    fill[n] = 1.0;
    ++voxels;
  });
  ASSERT_GT(voxels, 20u); // a 4 mm tube about 10 mm long at 1 x 1 x 1.5 mm voxels
  const double ml = double(voxels) * s.grid.voxelVolumeMm3() / 1000.0;
  const auto r = anatomy::classifyLeaks(ctAnatomy(), fill, {}, {});
  std::printf("cement in the vein: %zu voxels, %.4f ml; leaked %.4f ml, venous %.4f ml in %zu sites\n", voxels, ml,
              r.leakedMl, r.volumeMlByKind.at("venous"), r.sites.size());
  EXPECT_NEAR(r.leakedMl, ml, 1e-12);
  EXPECT_EQ(r.insideMl, 0.0);
  ASSERT_FALSE(r.sites.empty());
  EXPECT_EQ(r.sites[0].kind, "venous") << r.toJson().dump();
  EXPECT_GE(r.volumeMlByKind.at("venous"), 0.9 * ml) << r.toJson().dump();
}

// (g) With a label map made from the analytic geometry, every labelled voxel carries its label's class (exact),
// and the tip rules follow the labels.
TEST(VertebraAnatomy, LabelMapGivesTheSameClasses) {
  const auto& s = scene();
  const auto& t = *s.truth;
  // Labels in TotalSegmentator's numbering: L1 (31) the body with its fat and vein, L2 (30) and T12 (32) the
  // neighbours, 79 the cord (canal), 63 the vena cava for the vein outside; discs by a table key.
  std::vector<std::int32_t> labels(s.grid.count(), 0);
  s.forEach([&](std::size_t n, const P& p, const std::array<P, 8>&) {
    const double dz = p[2] - t.c[2];
    if (t.radial(p) <= 1 && std::abs(dz) <= kH) labels[n] = 31;
    else if (t.veinDistance(p) <= kVeinR) labels[n] = 63;
    else if (t.radial(p) <= 1 && dz > kH && dz <= kH + kDiscH) labels[n] = 200;
    else if (t.radial(p) <= 1 && dz < -kH && dz >= -kH - kDiscH) labels[n] = 201;
    else if (t.radial(p) <= 1 && dz > kH + kDiscH) labels[n] = 32;
    else if (t.radial(p) <= 1 && dz < -kH - kDiscH) labels[n] = 30;
    else if (std::hypot(p[0] - t.canal[0], p[1] - t.canal[1]) <= kCanalR && std::abs(dz) <= 0.8 * kH) labels[n] = 79;
  });
  anatomy::LabelTable table = anatomy::LabelTable::totalSegmentator();
  const auto extra = anatomy::LabelTable::fromJson(nlohmann::json{{"disc", {200, 201}}});
  table.classes.insert(extra.classes.begin(), extra.classes.end());
  const auto a = anatomy::classifyAnatomyFromLabels(s.hu.data(), labels.data(), s.grid, t.c, table, s.ao);
  EXPECT_EQ(a.rule, "labels");
  std::size_t wrong = 0;
  for (std::size_t n = 0; n < labels.size(); ++n) {
    const int l = labels[n];
    const TissueClass expected = l == 31                 ? TissueClass::TargetVertebra
                                 : l == 30 || l == 32    ? TissueClass::OtherBone
                                 : l == 63               ? TissueClass::Vessel
                                 : l == 200 || l == 201  ? TissueClass::Disc
                                 : l == 79               ? TissueClass::Canal
                                                         : TissueClass::OtherSoftTissue; // no air in the phantom
    if (a.at(n) != expected) ++wrong;
  }
  EXPECT_EQ(wrong, 0u);
  // The tip in the fat is in L1 (accepted); in the disc the nearest vertebra is the target and the tip refused.
  EXPECT_EQ(anatomy::requireTipInVertebra(a, s.hu.data(), t.fat, false), TissueClass::TargetVertebra);
  const P discTip{t.c[0], t.c[1], 0.5 * (t.upper[0] + t.upper[1])};
  const auto b = anatomy::classifyAnatomyFromLabels(s.hu.data(), labels.data(), s.grid, discTip, table, s.ao);
  EXPECT_TRUE(b.targetFound);
  EXPECT_THROW(anatomy::requireTipInVertebra(b, s.hu.data(), discTip, false), std::invalid_argument);
  // The same disc ball as above: one disc site under the labels too.
  std::vector<double> fill, arrival;
  ball(discTip, 3.0, fill, arrival);
  const auto r = anatomy::classifyLeaks(a, fill, arrival, {});
  ASSERT_EQ(r.sites.size(), 1u);
  EXPECT_EQ(r.sites[0].kind, "disc");
  EXPECT_EQ(r.rule, "labels");
  EXPECT_THROW(anatomy::LabelTable::fromJson(nlohmann::json{{"discs", {1}}}), std::invalid_argument);
}
