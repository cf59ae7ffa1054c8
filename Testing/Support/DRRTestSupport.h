// Support for the DRR tests: analytic phantoms voxelised into vtkImageData (each voxel's HU is the
// average over sub-samples of the phantom at physical positions, origin, spacing and direction matrix
// honoured, so a sphere's surface is partial-volumed rather than a staircase), and vtkDRRFilter run
// into a plain pixel array with the measures the tests read from it.
#pragma once

#include "cementsph/drr/DRRGeometry.h"

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include <array>
#include <functional>
#include <vector>

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

// A DRR as numbers: pixel (i, j) at v[j * cols + i], j = 0 the bottom row.
struct Drr {
  int cols = 0, rows = 0;
  double pixelW = 0, pixelH = 0;
  std::vector<float> v;
  double at(int i, int j) const { return v[static_cast<std::size_t>(j) * cols + i]; }
  double sum() const;
  // Intensity-weighted centroid (i, j) in pixels, and radius of gyration in pixels.
  std::array<double, 3> moments() const;
};

// vtkDRRFilter with geometry g (threads 0: OpenMP's default); checks the output is 2-D float.
Drr project(vtkImageData* volume, const drr::DRRGeometry& g, int threads = 0);

// A square detector of n x n pixels, sizeMm wide, sad/sid defaults.
drr::DRRGeometry detector(int n, double sizeMm, bool parallel, const Vec3& iso = {0, 0, 0});

} // namespace cementsph::drrtest
