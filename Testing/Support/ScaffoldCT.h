// A synthetic porous CT for the scene tests: a cubic scaffold of solid rods (1000 HU) along x, y and z, pores
// at -100 HU. Rods `rod` voxels thick every `period` voxels.
#pragma once

#include "cementsph/imaging/ImageTypes.h"

namespace cementsph::scene::testing {

inline bool scaffoldRod(int i, int j, int k, int period = 10, int rod = 3) {
  const bool a = i % period < rod, b = j % period < rod, c = k % period < rod;
  return (a && b) || (b && c) || (a && c);
}

// n^3 voxels of spacingMm, origin 0, identity direction, every voxel at hu.
inline imaging::ImageType::Pointer cube(int n, double spacingMm, float hu) {
  auto img = imaging::ImageType::New();
  imaging::ImageType::RegionType region;
  imaging::ImageType::SizeType size;
  size.Fill(itk::SizeValueType(n));
  region.SetSize(size);
  img->SetRegions(region);
  img->SetSpacing(spacingMm);
  img->Allocate();
  img->FillBuffer(hu);
  return img;
}

inline imaging::ImageType::Pointer scaffold(int n = 40, double spacingMm = 0.5, int period = 10, int rod = 3) {
  auto img = cube(n, spacingMm, -100.f);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) img->SetPixel({{i, j, k}}, scaffoldRod(i, j, k, period, rod) ? 1000.f : -100.f);
  return img;
}

} // namespace cementsph::scene::testing
