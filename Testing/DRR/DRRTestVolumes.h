// Analytic phantoms voxelised into vtkImageData for the DRR tests. Each voxel's HU is the average over
// sub-samples of the phantom at physical positions (origin, spacing and direction matrix honoured), so
// a sphere's surface is partial-volumed rather than a staircase.
#pragma once

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include <array>
#include <functional>

namespace cementsph::drrtest {

using Vec3 = std::array<double, 3>;
using Phantom = std::function<double(const Vec3&)>; // HU at a physical point (mm)

struct VolumeGrid {
  std::array<int, 3> dims{64, 64, 64};
  Vec3 spacing{1, 1, 1};
  Vec3 origin{0, 0, 0};
  std::array<double, 9> direction{1, 0, 0, 0, 1, 0, 0, 0, 1}; // row-major, columns = index axes
  int subsamples = 3;                                          // per axis, per voxel
};

// A grid of dims voxels whose centre (of the voxel box) lies at centreMm.
VolumeGrid centredGrid(const std::array<int, 3>& dims, const Vec3& spacing, const Vec3& centreMm);

vtkSmartPointer<vtkImageData> voxelise(const VolumeGrid& grid, const Phantom& phantom);

// Balls of given HU in air (-1000 HU); later balls overwrite earlier ones.
struct Ball {
  Vec3 centre;
  double radius;
  double hu;
};
Phantom balls(std::vector<Ball> list);

} // namespace cementsph::drrtest
