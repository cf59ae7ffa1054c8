#include "cementsph/scene/AxisAlignedCT.h"

#include "cementsph/imaging/AffineRegistration.h"

#include <itkIdentityTransform.h>

#include <algorithm>
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

imaging::ImageType::ConstPointer axisAligned(const imaging::ImageType* ct) {
  if (!ct) throw std::invalid_argument("CT: no image");
  if (isAxisAligned(ct)) return ct;
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
  const auto& spacing = ct->GetSpacing();
  const double h = std::min({spacing[0], spacing[1], spacing[2]});
  auto grid = imaging::ImageType::New();
  imaging::ImageType::RegionType out;
  imaging::ImageType::SizeType size;
  imaging::ImageType::PointType origin;
  // The grid's nodes pass through the CT's first voxel centre, so that along an axis the rotation keeps
  // (a series tilted about one axis) the voxels coincide with the CT's and nothing is interpolated there.
  const auto& first = ct->GetOrigin();
  for (unsigned a = 0; a < 3; ++a) {
    const double below = std::ceil((first[a] - lo[int(a)]) / h - 0.5 - 1e-9); // nodes from the box's low edge
    origin[a] = first[a] - below * h;
    size[a] = itk::SizeValueType(std::max(1.0, std::ceil((hi[int(a)] - origin[a]) / h + 0.5 - 1e-9)));
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
