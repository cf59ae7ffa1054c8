#include "cementsph/scene/AxisAlignedCT.h"

#include "cementsph/imaging/AffineRegistration.h"

#include <itkIdentityTransform.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace cementsph::scene {

bool isAxisAligned(const imaging::ImageType* ct) {
  const auto& d = ct->GetDirection();
  for (unsigned r = 0; r < 3; ++r)
    for (unsigned c = 0; c < 3; ++c)
      if (std::abs(d[r][c] - (r == c ? 1.0 : 0.0)) > 1e-6) return false;
  return true;
}

std::optional<AxisPermutation> axisPermutation(const imaging::ImageType* ct) {
  const auto& d = ct->GetDirection();
  AxisPermutation p;
  std::array<bool, 3> rowUsed{false, false, false};
  for (unsigned a = 0; a < 3; ++a) { // column a: where voxel axis a points
    int nonZero = 0;
    for (unsigned r = 0; r < 3; ++r) {
      const double v = d[r][a];
      if (std::abs(v) <= 1e-6) continue;
      if (std::abs(std::abs(v) - 1.0) > 1e-6 || rowUsed[r]) return std::nullopt;
      rowUsed[r] = true;
      p.axis[a] = r;
      p.sign[a] = v > 0 ? 1 : -1;
      ++nonZero;
    }
    if (nonZero != 1) return std::nullopt;
  }
  return p;
}

namespace {

// The same voxels with their axes permuted and flipped so that the direction is the identity: a copy, no
// interpolation, so a flipped or axis-swapped series gives the axial series' array exactly.
imaging::ImageType::Pointer reorient(const imaging::ImageType* ct, const AxisPermutation& p) {
  const auto region = ct->GetBufferedRegion();
  if (region != ct->GetLargestPossibleRegion())
    throw std::invalid_argument("CT: only part of the volume is in memory; load the whole series");
  const auto inSize = region.GetSize();
  const auto inStart = region.GetIndex();
  std::array<unsigned, 3> from{}; // patient axis r is voxel axis from[r] of the CT
  for (unsigned a = 0; a < 3; ++a) from[p.axis[a]] = a;
  imaging::ImageType::SizeType size;
  imaging::ImageType::SpacingType spacing;
  for (unsigned r = 0; r < 3; ++r) {
    size[r] = inSize[from[r]];
    spacing[r] = ct->GetSpacing()[from[r]];
  }
  // The new first voxel is the CT's voxel at the low end of every patient axis: its first voxel along an
  // axis that runs forwards, its last along one that runs backwards.
  imaging::ImageType::IndexType first;
  for (unsigned a = 0; a < 3; ++a)
    first[a] = inStart[a] + (p.sign[a] > 0 ? 0 : itk::IndexValueType(inSize[a]) - 1);
  imaging::ImageType::PointType origin;
  ct->TransformIndexToPhysicalPoint(first, origin);
  auto out = imaging::ImageType::New();
  imaging::ImageType::RegionType outRegion;
  outRegion.SetSize(size);
  out->SetRegions(outRegion);
  out->SetSpacing(spacing);
  out->SetOrigin(origin); // direction: the identity (New()'s)
  out->Allocate();
  // Buffer strides of the CT's axes, and where output index 0 lies along each.
  const std::array<std::ptrdiff_t, 3> stride{1, std::ptrdiff_t(inSize[0]), std::ptrdiff_t(inSize[0] * inSize[1])};
  std::array<std::ptrdiff_t, 3> step{}; // buffer step per output index along patient axis r
  std::ptrdiff_t base = 0;
  for (unsigned a = 0; a < 3; ++a) {
    step[p.axis[a]] = p.sign[a] * stride[a];
    if (p.sign[a] < 0) base += std::ptrdiff_t(inSize[a] - 1) * stride[a];
  }
  const float* in = ct->GetBufferPointer();
  float* o = out->GetBufferPointer();
  for (std::ptrdiff_t k = 0; k < std::ptrdiff_t(size[2]); ++k)
    for (std::ptrdiff_t j = 0; j < std::ptrdiff_t(size[1]); ++j) {
      std::ptrdiff_t src = base + k * step[2] + j * step[1];
      for (std::ptrdiff_t i = 0; i < std::ptrdiff_t(size[0]); ++i, src += step[0]) *o++ = in[src];
    }
  return out;
}

} // namespace

imaging::ImageType::ConstPointer axisAligned(const imaging::ImageType* ct) {
  if (!ct) throw std::invalid_argument("CT: no image");
  if (isAxisAligned(ct)) return ct;
  // Flipped or swapped axes: the voxels already lie on an axis-aligned grid, so resampling would only blur
  // them (trilinear, and onto the smallest spacing).
  if (const auto permutation = axisPermutation(ct)) return imaging::ImageType::ConstPointer(reorient(ct, *permutation));
  const auto& d = ct->GetDirection();
  for (unsigned a = 0; a < 3; ++a)
    for (unsigned b = 0; b < 3; ++b) {
      double dot = 0;
      for (unsigned r = 0; r < 3; ++r) dot += d[r][a] * d[r][b];
      if (std::abs(dot - (a == b ? 1.0 : 0.0)) > 1e-4) {
        std::ostringstream m;
        m << "CT: its direction matrix is not a rotation (columns " << a << " and " << b << " have dot product " << dot
          << "): the series' geometry is inconsistent; re-export it from the scanner or resample it first";
        throw std::invalid_argument(m.str());
      }
    }
  // The CT's box in the patient frame: its 8 corners (voxel edges, not centres).
  const auto region = ct->GetLargestPossibleRegion();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int corner = 0; corner < 8; ++corner) {
    itk::ContinuousIndex<double, 3> index;
    for (unsigned a = 0; a < 3; ++a)
      index[a] = double(region.GetIndex()[a]) - 0.5 + ((corner >> a) & 1 ? double(region.GetSize()[a]) : 0.0);
    imaging::ImageType::PointType p;
    ct->TransformContinuousIndexToPhysicalPoint(index, p);
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[unsigned(a)]);
      hi[a] = std::max(hi[a], p[unsigned(a)]);
    }
  }
  // Each patient axis takes the spacing of the CT axis that runs most nearly along it (a 20 degree gantry tilt
  // of a 1 x 1 x 1.5 mm series: 1 x 1 x 1.5 mm), not the smallest spacing on all three: the runs cost in
  // proportion to the voxels of their region, and an isotropic grid at the smallest spacing gave a tilted
  // 1 x 1 x 1.5 mm series 1.5x the axial series' voxels (plan 2.0-2.5x the axial's time) for detail the series
  // does not have along its coarse axis. The tilted box's bounding box adds corners outside the scan, filled with
  // kOutsideScanHu (air): the bone rule cuts air off its cube about the tip (VertebraAnatomy.cpp), so they cost an
  // injection nothing (a 20 degree tilt planned at 0.9-1.17x the axial plan's CPU, PlanObliqueTest).
  const auto& spacing = ct->GetSpacing();
  imaging::ImageType::SpacingType h;
  for (unsigned r = 0; r < 3; ++r) {
    unsigned along = 0;
    for (unsigned a = 1; a < 3; ++a)
      if (std::abs(d[r][a]) > std::abs(d[r][along])) along = a;
    h[r] = spacing[along];
  }
  auto grid = imaging::ImageType::New();
  imaging::ImageType::RegionType out;
  imaging::ImageType::SizeType size;
  imaging::ImageType::PointType origin;
  // The grid's nodes pass through the CT's first voxel centre, so that along an axis the rotation keeps
  // (a series tilted about one axis) the voxels coincide with the CT's and nothing is interpolated there.
  const auto& first = ct->GetOrigin();
  for (unsigned a = 0; a < 3; ++a) {
    const double below = std::ceil((first[a] - lo[int(a)]) / h[a] - 0.5 - 1e-9); // nodes from the box's low edge
    origin[a] = first[a] - below * h[a];
    size[a] = itk::SizeValueType(std::max(1.0, std::ceil((hi[int(a)] - origin[a]) / h[a] + 0.5 - 1e-9)));
  }
  out.SetSize(size);
  grid->SetRegions(out);
  grid->SetSpacing(h);
  grid->SetOrigin(origin);
  auto identity = itk::IdentityTransform<double, 3>::New();
  imaging::ImageType::Pointer resampled = imaging::resampleOnto(ct, grid, identity, kOutsideScanHu);
  return resampled;
}

} // namespace cementsph::scene
