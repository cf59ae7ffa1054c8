// A CT in any orientation, for the injection: scanners write oblique or rotated series (a direction matrix
// other than the identity), and the voxel models work on grids whose axes are the patient frame's (LPS).
// Such a CT is resampled onto an axis-aligned grid in the same physical space: isotropic voxels of the
// CT's smallest spacing, covering the CT's whole box, trilinear interpolation (imaging::resampleOnto), and
// -1000 HU (air) outside the scan. Everything after that (tip, results, simulated CT) is in the CT's patient
// frame in mm, as for an axis-aligned CT.
#pragma once

#include "cementsph/imaging/ImageTypes.h"

namespace cementsph::scene {

constexpr float kOutsideScanHu = -1000.0f;

// True when the direction matrix is the identity (to 1e-6).
bool isAxisAligned(const imaging::ImageType* ct);
// The CT itself when axis-aligned, else its axis-aligned resampling. Throws std::invalid_argument (one line)
// for a direction matrix that is not a rotation (not orthonormal: a sheared or mirrored-and-scaled series).
imaging::ImageType::ConstPointer axisAligned(const imaging::ImageType* ct);

} // namespace cementsph::scene
