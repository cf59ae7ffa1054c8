#include "cementsph/scene/SimulatedCT.h"

#include <stdexcept>

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
  const auto start = ct->GetLargestPossibleRegion().GetIndex();
  for (int k = 0; k < solid.grid.size[2]; ++k)
    for (int j = 0; j < solid.grid.size[1]; ++j)
      for (int i = 0; i < solid.grid.size[0]; ++i) {
        imaging::ImageType::IndexType src;
        src[0] = start[0] + solid.roiStart[0] + i;
        src[1] = start[1] + solid.roiStart[1] + j;
        src[2] = start[2] + solid.roiStart[2] + k;
        const double added = rho.empty() ? 0.0 : huPerRelativeDensity * rho[solid.grid.index(i, j, k)] / rho0;
        simCt->SetPixel({{i, j, k}}, float(double(ct->GetPixel(src)) + added));
      }
  return simCt;
}

} // namespace cementsph::scene
