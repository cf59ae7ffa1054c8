#include "cementsph/drr/DetectorFrame.h"

#include <cmath>

namespace cementsph::drr {

namespace {
// Parallel rays are segments this long on each side of the detector plane: longer than any volume.
constexpr double kParallelHalfLengthMm = 1.0e6;
} // namespace

Ray DetectorFrame::ray(int i, int j) const {
  Ray r;
  Vec3 pixel;
  for (int a = 0; a < 3; ++a) pixel[a] = pixel00[a] + i * stepI[a] + j * stepJ[a];
  if (parallel) {
    r.direction = beam;
    for (int a = 0; a < 3; ++a) r.origin[a] = pixel[a] - kParallelHalfLengthMm * beam[a];
    r.tMax = 2.0 * kParallelHalfLengthMm;
    return r;
  }
  r.origin = source;
  const Vec3 d{pixel[0] - source[0], pixel[1] - source[1], pixel[2] - source[2]};
  const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  r.direction = {d[0] / length, d[1] / length, d[2] / length};
  r.tMax = length;
  return r;
}

} // namespace cementsph::drr
