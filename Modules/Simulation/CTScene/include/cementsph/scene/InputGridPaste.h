// The simulated CT back on the CT's own grid. The runner works on the axis-aligned CT (AxisAlignedCT.h):
// the CT itself, its exact reorientation (flipped/swapped axes) or its resampling (oblique), and its
// simulated CT covers the region of interest of THAT grid. Its voxel indices mean nothing on the input's
// grid once the direction is not the identity, so the result goes back through physical points (LPS, mm).
#pragma once

#include "cementsph/imaging/ImageTypes.h"

namespace cementsph::scene {

// The pre-injection HU of `input` at the voxel centres of `grid` (any image with identity direction lying on
// the aligned CT's grid, e.g. the runner's simulated CT): what axisAligned(input) holds there, without
// building all of it. Identity or signed-permutation direction: the input's voxel at that centre (the centres
// coincide, so this is exact); oblique: trilinear interpolation, kOutsideScanHu outside the scan, as
// axisAligned resamples (equal up to the round-off of sampling the same point twice).
imaging::ImageType::Pointer alignedBackgroundOn(const imaging::ImageType* input, const imaging::ImageType* grid);

// An image on the input's grid (its region, origin, spacing and direction): the input's HU everywhere, and
// at every input voxel whose centre lies in the simulated image's box (its voxel boxes), the input's HU plus
// the change the injection made there, (simulated - background) sampled at that centre. Where the centre
// falls on a simulated voxel centre (to 1e-6 voxel: the axial and exactly reoriented cases) that voxel's
// change is taken as it is (the result then equals the simulated HU exactly); elsewhere (oblique) the
// change is interpolated trilinearly between the simulated voxel centres, clamped at the box's edge.
// simulated: identity direction, any origin/spacing; background: the pre-injection HU on the same grid
// (alignedBackgroundOn). Every index is bounds-checked; a simulated image outside the input writes nothing.
// Throws std::invalid_argument (one line) when simulated is oblique or the background is on another grid.
imaging::ImageType::Pointer pasteOntoInputGrid(const imaging::ImageType* input, const imaging::ImageType* simulated,
                                               const imaging::ImageType* background);

} // namespace cementsph::scene
