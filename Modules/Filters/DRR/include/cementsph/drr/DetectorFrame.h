// The DRR detector as vectors in patient coordinates (made by DRRGeometry::frame()).
#pragma once

#include "cementsph/drr/Ray.h"

namespace cementsph::drr {

// The detector as vectors, computed once per image (a per-ray recomputation of the trigonometry
// would cost about as much as the voxel walk itself).
struct DetectorFrame {
  Vec3 source{};    // ray origin (cone beam)
  Vec3 beam{};      // unit, source -> detector
  Vec3 pixel00{};   // centre of output pixel (0, 0)
  Vec3 stepI{};     // from pixel (i, j) to (i + 1, j), mm
  Vec3 stepJ{};     // from pixel (i, j) to (i, j + 1), mm
  bool parallel = false;

  // The ray for output pixel (i, j): cone beam, source to pixel; parallel beam, a segment along the
  // beam long enough to cross any volume within 1e6 mm of the isocentre.
  Ray ray(int i, int j) const;
};

} // namespace cementsph::drr
