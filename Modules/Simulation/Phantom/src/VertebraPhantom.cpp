#include "cementsph/phantom/VertebraPhantom.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace cementsph::phantom {

namespace {
constexpr double kA = 20.0, kB = 15.0, kHalfHeight = 12.5; // body semi-axes and half height [mm]
constexpr double kCortex = 1.0, kCanalRadius = 8.0, kArchOuter = 12.0;
} // namespace

void VertebraOptions::validate() const {
  for (int a = 0; a < 3; ++a)
    if (!(spacingMm[std::size_t(a)] >= 0.2 && spacingMm[std::size_t(a)] <= 3.0))
      throw std::invalid_argument("spacing_mm must be 0.2 .. 3 mm per axis");
  if (!(fieldMm[0] >= 50 && fieldMm[1] >= 60 && fieldMm[2] >= 30 && fieldMm[0] <= 300 && fieldMm[1] <= 300 &&
        fieldMm[2] <= 300))
    throw std::invalid_argument("field_mm must hold the vertebra: at least 50 x 60 x 30 mm, at most 300 mm");
  if (!(trabecularCentreHu > softTissueHu && trabecularRimHu >= trabecularCentreHu && corticalHu > trabecularRimHu))
    throw std::invalid_argument("hu values must rise: soft tissue < trabecular centre <= rim < cortex");
  if (!(foramenDiameterMm >= 0 && foramenDiameterMm <= 10)) throw std::invalid_argument("foramen_diameter_mm must be 0 .. 10 mm");
  if (!(noiseHu >= 0 && noiseHu <= 200)) throw std::invalid_argument("noise_hu must be 0 .. 200 HU");
  // The variant: the fat sphere must stay inside the trabecular bone, the discs and the neighbours' end plates
  // inside the field.
  if (!(marrowFatRadiusMm == 0 || (marrowFatRadiusMm >= 1 && marrowFatRadiusMm <= 6)))
    throw std::invalid_argument("marrow_fat_radius_mm must be 0 (none) or 1 .. 6 mm");
  if (!(marrowFatHu > -200 && marrowFatHu < trabecularCentreHu))
    throw std::invalid_argument("marrow_fat_hu must be above -200 HU and below trabecular_centre_hu");
  if (!(discHeightMm == 0 || (discHeightMm >= 4 && discHeightMm <= 15)))
    throw std::invalid_argument("disc_height_mm must be 0 (none) or 4 .. 15 mm");
  if (discHeightMm > 0 && !(fieldMm[2] >= 2 * kHalfHeight + 2 * (discHeightMm + 2 * kCortex)))
    throw std::invalid_argument("field_mm[2] must hold the body, both discs and the neighbours' end plates: at least " +
                                std::to_string(2 * kHalfHeight + 2 * (discHeightMm + 2 * kCortex)) + " mm");
  if (!(discHu > softTissueHu && discHu < corticalHu))
    throw std::invalid_argument("disc_hu must be between soft_tissue_hu and cortical_hu");
  if (!(veinRadiusMm == 0 || (veinRadiusMm >= 1 && veinRadiusMm <= 3)))
    throw std::invalid_argument("vein_radius_mm must be 0 (none) or 1 .. 3 mm");
  if (!(veinHu > -200 && veinHu < corticalHu)) throw std::invalid_argument("vein_hu must be above -200 HU and below cortical_hu");
}

nlohmann::json VertebraResult::toJson() const {
  nlohmann::json j = {{"body_centre_mm", bodyCentreMm},
          {"body_semi_axes_mm", {kA, kB, kHalfHeight}},
          {"cortex_mm", kCortex},
          {"canal_centre_mm", canalCentreMm},
          {"canal_radius_mm", kCanalRadius},
          {"foramen_mm", foramenMm},
          {"suggested_tip_mm", suggestedTipMm},
          {"suggested_direction", suggestedDirection},
          {"frame", "LPS mm: x to the patient's left, y posterior, z superior"}};
  // The variant's keys only where it is on: the default phantom's truth.json stays as it was.
  if (marrowFatRadiusMm > 0) j["marrow_fat"] = {{"centre_mm", marrowFatCentreMm}, {"radius_mm", marrowFatRadiusMm}};
  if (discHeightMm > 0)
    j["discs"] = {{"section", "the body's elliptic section"}, {"lower_z_mm", lowerDiscZMm}, {"upper_z_mm", upperDiscZMm}};
  if (veinRadiusMm > 0) j["vein"] = {{"start_mm", veinStartMm}, {"end_mm", veinEndMm}, {"radius_mm", veinRadiusMm}};
  return j;
}

VertebraResult makeVertebra(const VertebraOptions& o) {
  o.validate();
  VertebraResult r;
  const double cx = 0.5 * o.fieldMm[0], cz = 0.5 * o.fieldMm[2];
  const double cy = kB + 6.0; // the body's centre, 6 mm of soft tissue in front
  r.bodyCentreMm = {cx, cy, cz};
  r.canalCentreMm = {cx, cy + kB + kCanalRadius, cz};
  r.foramenMm = {cx, cy + kB - 0.5 * kCortex, cz};
  // Transpedicular: from posterior-left through the pedicle, the tip 3 mm left of and 9 mm behind the body's
  // centre, 6 mm in front of the posterior wall: 4 ml then reaches the foramen (the demo's leak). The shaft runs
  // back from the tip through the lateral part of the left pedicle: through the arch's wall beside the canal's
  // centre, 0.5 mm inside its outer edge (cx + kArchOuter - 0.5, the canal's y), so that at its closest the shaft's
  // axis is 1.8 mm outside the canal, more than an 11 G cannula's outer radius (1.52 mm). The earlier
  // (-0.3, -0.954) ran through the canal 10-15 mm behind the tip.
  r.suggestedTipMm = {cx + 3.0, cy + 9.0, cz};
  const double backX = kArchOuter - 0.5 - 3.0, backY = r.canalCentreMm[1] - r.suggestedTipMm[1];
  const double length = std::hypot(backX, backY);
  r.suggestedDirection = {-backX / length, -backY / length, 0.0};
  r.bodySemiAxesMm = {kA, kB, kHalfHeight};
  // The variant's geometry (fixed offsets from the body's centre, chosen so that fat and vein stay 3 mm apart
  // and the vein leaves through the posterolateral wall, clear of the posterior arch).
  r.marrowFatRadiusMm = o.marrowFatRadiusMm;
  r.marrowFatCentreMm = {cx + 7.0, cy - 3.0, cz + 2.0};
  r.discHeightMm = o.discHeightMm;
  r.lowerDiscZMm = {cz - kHalfHeight - o.discHeightMm, cz - kHalfHeight};
  r.upperDiscZMm = {cz + kHalfHeight, cz + kHalfHeight + o.discHeightMm};
  r.veinRadiusMm = o.veinRadiusMm;
  r.veinStartMm = {cx - 4.0, cy + 2.0, cz - 5.0};
  r.veinEndMm = {cx - 22.0, cy + 20.0, cz - 5.0};
  // Distance from a point to the vein's axis (a segment: the tube has round ends).
  auto veinDistance = [&](double x, double y, double z) {
    const double ux = r.veinEndMm[0] - r.veinStartMm[0], uy = r.veinEndMm[1] - r.veinStartMm[1],
                 uz = r.veinEndMm[2] - r.veinStartMm[2];
    const double px = x - r.veinStartMm[0], py = y - r.veinStartMm[1], pz = z - r.veinStartMm[2];
    double t = (px * ux + py * uy + pz * uz) / (ux * ux + uy * uy + uz * uz);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return std::sqrt((px - t * ux) * (px - t * ux) + (py - t * uy) * (py - t * uy) + (pz - t * uz) * (pz - t * uz));
  };
  auto inVein = [&](double x, double y, double z) { return o.veinRadiusMm > 0 && veinDistance(x, y, z) <= o.veinRadiusMm; };

  auto hu = [&](double x, double y, double z) -> double {
    const double ex = (x - cx) / kA, ey = (y - cy) / kB, ez = (z - cz) / kHalfHeight;
    const double radial = std::sqrt(ex * ex + ey * ey);
    // The body: trabecular inside, cortex in its outer kCortex (side wall and end plates).
    if (radial <= 1.0 && std::abs(ez) <= 1.0) {
      if (inVein(x, y, z)) return o.veinHu; // the vein runs through the trabecular bone and opens the wall
      const double wallDepth = std::min((1.0 - radial) * std::min(kA, kB), (1.0 - std::abs(ez)) * kHalfHeight);
      const bool foramen = o.foramenDiameterMm > 0 &&
                           std::hypot(x - r.foramenMm[0], z - r.foramenMm[2]) <= 0.5 * o.foramenDiameterMm &&
                           y > cy;
      if (wallDepth < kCortex) return foramen ? o.canalHu : o.corticalHu;
      if (o.marrowFatRadiusMm > 0 &&
          std::hypot(x - r.marrowFatCentreMm[0], y - r.marrowFatCentreMm[1], z - r.marrowFatCentreMm[2]) <=
              o.marrowFatRadiusMm)
        return o.marrowFatHu;
      const double s = radial * radial;
      return o.trabecularCentreHu + (o.trabecularRimHu - o.trabecularCentreHu) * std::min(1.0, s);
    }
    if (inVein(x, y, z)) return o.veinHu;
    // Discs above and below, then the neighbouring bodies (end plate and side wall cortex, trabecular inside).
    if (o.discHeightMm > 0 && radial <= 1.0) {
      const double above = std::abs(z - cz) - kHalfHeight; // > 0 here: outside the body's height
      if (above <= o.discHeightMm) return o.discHu;
      const double depth = above - o.discHeightMm;           // into the neighbour
      if (depth <= 2 * kHalfHeight) {
        // The neighbours' end plates are 2 mm thick, so that one voxel of any 1.5 mm slicing is mostly cortex.
        const double sideDepth = (1.0 - radial) * std::min(kA, kB), plateDepth = std::min(depth, 2 * kHalfHeight - depth);
        if (sideDepth < kCortex || plateDepth < 2 * kCortex) return o.corticalHu;
        return o.trabecularCentreHu + (o.trabecularRimHu - o.trabecularCentreHu) * std::min(1.0, radial * radial);
      }
    }
    // The canal and the posterior arch around it (pedicles and lamina), behind the body, within its height.
    const double rc = std::hypot(x - r.canalCentreMm[0], y - r.canalCentreMm[1]);
    if (std::abs(z - cz) <= kHalfHeight * 0.8) {
      if (rc <= kCanalRadius) return o.canalHu;
      if (rc <= kArchOuter && y >= r.canalCentreMm[1] - kCanalRadius - 0.5) return o.corticalHu;
    }
    return o.softTissueHu;
  };

  auto img = imaging::ImageType::New();
  imaging::ImageType::RegionType region;
  imaging::ImageType::SizeType size;
  for (unsigned a = 0; a < 3; ++a) size[a] = itk::SizeValueType(std::lround(o.fieldMm[a] / o.spacingMm[a]));
  region.SetSize(size);
  img->SetRegions(region);
  img->SetSpacing(o.spacingMm.data());
  img->Allocate();
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> noise(0.0, o.noiseHu > 0 ? o.noiseHu : 1.0);
  const int ss = 3;
  for (unsigned k = 0; k < size[2]; ++k)
    for (unsigned j = 0; j < size[1]; ++j)
      for (unsigned i = 0; i < size[0]; ++i) {
        double sum = 0;
        for (int c = 0; c < ss; ++c)
          for (int b = 0; b < ss; ++b)
            for (int a = 0; a < ss; ++a)
              sum += hu((i + (a + 0.5) / ss - 0.5) * o.spacingMm[0], (j + (b + 0.5) / ss - 0.5) * o.spacingMm[1],
                        (k + (c + 0.5) / ss - 0.5) * o.spacingMm[2]);
        double v = sum / (ss * ss * ss);
        if (o.noiseHu > 0) v += noise(rng);
        img->SetPixel({{long(i), long(j), long(k)}}, float(std::round(v)));
      }
  r.ct = img;
  return r;
}

} // namespace cementsph::phantom
