// A CT volume seen as linear attenuation (1/mm), and the exact line integral through it.
// HU -> mu as plastimatch ("water at 50 keV"): mu = 0.022 /mm * (1 + HU/1000) for HU > -800, else 0.
// The line integral is an exact voxel walk (Amanatides-Woo 3-D DDA, i.e. Siddon's method): every voxel
// the ray crosses contributes mu * (length of the ray inside it, mm), so there is no sampling error.
// The walk runs in continuous index space, so any origin, spacing and direction matrix (even a
// non-orthogonal one) is handled by one affine map of the ray; lengths stay in mm because the ray
// parameter is the physical distance along the ray.
#pragma once

#include "cementsph/drr/Ray.h"

#include <cstddef>
#include <vector>

class vtkImageData;

namespace cementsph::drr {

class AttenuationVolume {
public:
  static constexpr double kMuWaterPerMm = 0.022;
  static constexpr double kAirThresholdHU = -800.0;
  static double muFromHU(double hu) {
    return hu > kAirThresholdHU ? kMuWaterPerMm * (1.0 + hu / 1000.0) : 0.0;
  }

  // Reads the first scalar component of image (any numeric type) as HU. Throws std::invalid_argument
  // for an image without scalars, with no voxels or with a singular index-to-physical matrix.
  // A single-component float image is read in place: it must outlive this object, unchanged.
  AttenuationVolume(vtkImageData* image, int threads);
  AttenuationVolume(const AttenuationVolume&) = delete;
  AttenuationVolume& operator=(const AttenuationVolume&) = delete;

  // Integral of mu along the ray over [tMin, tMax] (dimensionless: 1/mm times mm).
  double lineIntegral(const Ray& ray) const;

  // Number of voxels with mu > 0 (HU > -800; 0: the volume is all air, every ray integrates to 0).
  std::size_t attenuatingVoxels() const { return attenuating_; }

private:
  // HU, converted to mu voxel by voxel during the walk (cheaper than a converted copy of the volume).
  const float* hu_ = nullptr;
  std::vector<float> ownedHU_; // only for inputs that are not single-component float
  int dims_[3] = {0, 0, 0};
  std::ptrdiff_t stride_[3] = {1, 0, 0};
  double physicalToIndex_[12] = {}; // 3x4 row-major: continuous index of a physical point, 0-based
  // Index box of the attenuating voxels: rays are clipped to it, so air around the object is skipped.
  int lo_[3] = {0, 0, 0};
  int hi_[3] = {-1, -1, -1};
  std::size_t attenuating_ = 0;
};

} // namespace cementsph::drr
