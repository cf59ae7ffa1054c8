#include "cementsph/scene/SimulatedCT.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace cementsph::scene {

imaging::ImageType::Pointer simulatedCtOnRoi(const imaging::ImageType* ct, const PorousSolid& solid,
                                             const std::vector<double>& rho, double huPerRelativeDensity,
                                             double rho0) {
  if (!rho.empty() && rho.size() != solid.grid.count())
    throw std::invalid_argument("simulatedCtOnRoi: the density has " + std::to_string(rho.size()) +
                                " values for " + std::to_string(solid.grid.count()) + " ROI voxels");
  auto simCt = imaging::ImageType::New();
  imaging::ImageType::RegionType region;
  imaging::ImageType::SizeType size;
  for (unsigned a = 0; a < 3; ++a) size[a] = itk::SizeValueType(solid.roiSize[a]);
  region.SetSize(size);
  simCt->SetRegions(region);
  simCt->SetSpacing(ct->GetSpacing());
  simCt->SetDirection(ct->GetDirection());
  imaging::ImageType::PointType origin;
  for (unsigned a = 0; a < 3; ++a) origin[a] = solid.grid.origin[int(a)] * 1e3;
  simCt->SetOrigin(origin);
  simCt->Allocate();
  for (int a = 0; a < 3; ++a)
    if (long(solid.grid.size[std::size_t(a)]) != long(solid.roiSize[std::size_t(a)]))
      throw std::invalid_argument("simulatedCtOnRoi: the region's grid and size differ");
  // Row by row through the buffers (issue 23: GetPixel and SetPixel per voxel were most of this pass on a
  // whole-scan region). The region lies inside the CT (PorousSolid clips it); ComputeOffset checks nothing, so
  // the rows' ends are checked here once.
  const auto start = ct->GetLargestPossibleRegion().GetIndex();
  const float* in = ct->GetBufferPointer();
  float* out = simCt->GetBufferPointer();
  const long nx = solid.grid.size[0];
  for (int k = 0; k < solid.grid.size[2]; ++k)
    for (int j = 0; j < solid.grid.size[1]; ++j) {
      imaging::ImageType::IndexType first, last;
      first[0] = start[0] + solid.roiStart[0];
      first[1] = start[1] + solid.roiStart[1] + j;
      first[2] = start[2] + solid.roiStart[2] + k;
      last = first;
      last[0] += nx - 1;
      if (!ct->GetBufferedRegion().IsInside(first) || !ct->GetBufferedRegion().IsInside(last))
        throw std::invalid_argument("simulatedCtOnRoi: the region leaves the CT's buffer");
      const float* from = in + ct->ComputeOffset(first);
      float* to = out + solid.grid.index(0, j, k);
      if (rho.empty()) {
        std::copy(from, from + nx, to);
        continue;
      }
      const double* r = rho.data() + solid.grid.index(0, j, k);
      for (long i = 0; i < nx; ++i) to[i] = float(double(from[i]) + huPerRelativeDensity * r[i] / rho0);
    }
  return simCt;
}

SparseDensity nonZeroDensity(const std::vector<double>& density) {
  SparseDensity sparse;
  for (std::size_t c = 0; c < density.size(); ++c)
    if (density[c] != 0) sparse.emplace_back(c, density[c]);
  return sparse;
}

imaging::ImageType::Pointer simulatedCtOnRoi(const imaging::ImageType* ct, const PorousSolid& solid,
                                             const SparseDensity& rho, double huPerRelativeDensity, double rho0) {
  const std::size_t count = solid.grid.count();
  for (std::size_t n = 0; n < rho.size(); ++n)
    if (rho[n].first >= count || (n > 0 && rho[n].first <= rho[n - 1].first))
      throw std::invalid_argument("simulatedCtOnRoi: the sparse density's voxel " + std::to_string(rho[n].first) +
                                  " is outside the " + std::to_string(count) + " ROI voxels or out of order");
  imaging::ImageType::Pointer simCt = simulatedCtOnRoi(ct, solid, std::vector<double>{}, huPerRelativeDensity, rho0);
  float* out = simCt->GetBufferPointer(); // the CT's values, as the dense version reads them
  // The dense version's expression, term for term; a voxel with no cement keeps the CT's value.
  for (const auto& [c, r] : rho) out[c] = float(double(out[c]) + huPerRelativeDensity * r / rho0);
  return simCt;
}

} // namespace cementsph::scene
