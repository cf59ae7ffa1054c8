// A CT in any orientation, for the injection: scanners write oblique, rotated, flipped or axis-swapped series
// (a direction matrix other than the identity), and the voxel models work on grids whose axes are the patient
// frame's (LPS). axisAligned() turns such a CT into an axis-aligned one in the same physical space:
//  * direction a signed permutation (entries 0/+-1 to 1e-6: flipped and/or swapped axes, e.g. a sagittal or
//    coronal series, or one stored feet-first): reoriented EXACTLY, the voxel array permuted and flipped, no
//    interpolation. The result has identity direction, the permuted spacing, and as origin the physical
//    position of its first voxel; every voxel keeps its value and its physical centre (to the 1e-6 of the
//    matrix times the CT's extent), so results equal the axial series'.
//  * truly oblique (any other rotation): resampled onto an axis-aligned grid: each patient axis at the spacing of
//    the CT axis most nearly along it, covering the CT's whole box, trilinear interpolation (imaging::resampleOnto), and
//    -1000 HU (air) outside the scan.
// Everything after that (tip, results, simulated CT) is in the CT's patient frame in mm, as for an axial CT.
#pragma once

#include "cementsph/imaging/ImageTypes.h"

#include <array>
#include <optional>

namespace cementsph::scene {

constexpr float kOutsideScanHu = -1000.0f;

// Voxel axis a of a CT runs along patient axis `axis[a]`, in the direction `sign[a]` (+1 or -1).
struct AxisPermutation {
  std::array<unsigned, 3> axis{};
  std::array<int, 3> sign{};
};

// True when the direction matrix is the identity (to 1e-6).
bool isAxisAligned(const imaging::ImageType* ct);
// The signed permutation a direction matrix is (every entry within 1e-6 of 0, +1 or -1, one non-zero per
// row and column), or nothing for an oblique one.
std::optional<AxisPermutation> axisPermutation(const imaging::ImageType* ct);
// The CT itself when axis-aligned, its exact reorientation for a signed permutation, else its axis-aligned
// resampling. Throws std::invalid_argument (one line) for a direction matrix that is not orthonormal (a
// sheared or mirrored-and-scaled series).
imaging::ImageType::ConstPointer axisAligned(const imaging::ImageType* ct);

} // namespace cementsph::scene
