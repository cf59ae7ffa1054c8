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
}

nlohmann::json VertebraResult::toJson() const {
  return {{"body_centre_mm", bodyCentreMm},
          {"body_semi_axes_mm", {kA, kB, kHalfHeight}},
          {"cortex_mm", kCortex},
          {"canal_centre_mm", canalCentreMm},
          {"canal_radius_mm", kCanalRadius},
          {"foramen_mm", foramenMm},
          {"suggested_tip_mm", suggestedTipMm},
          {"suggested_direction", suggestedDirection},
          {"frame", "LPS mm: x to the patient's left, y posterior, z superior"}};
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
  // centre, 6 mm in front of the posterior wall: 4 ml then reaches the foramen (the demo's leak).
  r.suggestedTipMm = {cx + 3.0, cy + 9.0, cz};
  const double dx = -0.3, dy = -0.954;
  r.suggestedDirection = {dx, dy, 0.0};

  auto hu = [&](double x, double y, double z) -> double {
    const double ex = (x - cx) / kA, ey = (y - cy) / kB, ez = (z - cz) / kHalfHeight;
    const double radial = std::sqrt(ex * ex + ey * ey);
    // The body: trabecular inside, cortex in its outer kCortex (side wall and end plates).
    if (radial <= 1.0 && std::abs(ez) <= 1.0) {
      const double wallDepth = std::min((1.0 - radial) * std::min(kA, kB), (1.0 - std::abs(ez)) * kHalfHeight);
      const bool foramen = o.foramenDiameterMm > 0 &&
                           std::hypot(x - r.foramenMm[0], z - r.foramenMm[2]) <= 0.5 * o.foramenDiameterMm &&
                           y > cy;
      if (wallDepth < kCortex) return foramen ? o.canalHu : o.corticalHu;
      const double s = radial * radial;
      return o.trabecularCentreHu + (o.trabecularRimHu - o.trabecularCentreHu) * std::min(1.0, s);
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
