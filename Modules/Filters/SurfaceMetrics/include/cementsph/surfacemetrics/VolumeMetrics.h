// Metrics of segmentation volumes (0/1 masks as vtkImageData, any scalar type, non-zero = inside):
// overlap (Dice, Jaccard), cement volume, centroid, and the paper's mean spreading distance (mean
// distance of the cement voxel centres from the injection point). Physical coordinates in mm,
// with the image's origin, spacing and direction matrix.
#pragma once

#include <vtkImageData.h>

#include <array>
#include <cstddef>

namespace cementsph::surfacemetrics {

using Point3 = std::array<double, 3>;

struct Overlap {
  std::size_t voxelsA = 0, voxelsB = 0, voxelsBoth = 0;
  double dice = 0.0;    // 2|A&B| / (|A|+|B|); 1 when both are empty
  double jaccard = 0.0; // |A&B| / |A|B|;   1 when both are empty
};

// Throws std::invalid_argument if the two masks are not on one grid.
Overlap overlap(vtkImageData* a, vtkImageData* b);

std::size_t countVoxels(vtkImageData* mask);
double volumeMl(vtkImageData* mask); // 1 ml = 1000 mm^3

// Physical centre of voxel (i,j,k): origin + D (spacing * ijk).
Point3 voxelCentre(vtkImageData* image, int i, int j, int k);

// Centroid of the inside voxel centres; {0,0,0} with ok=false for an empty mask.
Point3 centroidMm(vtkImageData* mask, bool* ok = nullptr);

// Mean distance of inside voxel centres from point; 0 for an empty mask.
double meanSpreadingDistanceMm(vtkImageData* mask, const Point3& injectionPointMm);

} // namespace cementsph::surfacemetrics
