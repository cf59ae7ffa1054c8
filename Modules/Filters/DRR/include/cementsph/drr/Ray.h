// A ray segment in patient (volume physical) coordinates, mm.
#pragma once

#include <array>

namespace cementsph::drr {

using Vec3 = std::array<double, 3>;

// point(t) = origin + t * direction (unit), t in [tMin, tMax] mm: t is the physical distance along
// the ray, so segment lengths in t are lengths in mm.
struct Ray {
  Vec3 origin{};
  Vec3 direction{};
  double tMin = 0.0;
  double tMax = 0.0;
};

} // namespace cementsph::drr
