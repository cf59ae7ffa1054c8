// Surface-to-surface distances, the paper's error measure (Basafa et al. 2013): for every vertex of
// one isosurface its distance to the other surface, both ways; mean, max and std each way; the
// error is the larger of the two means. Also the Hausdorff distance and its 95th percentile.
// Point-to-surface distance uses one vtkStaticCellLocator per thread (vtkDistancePolyDataFilter is
// far slower: seconds for 16k points).
#pragma once

#include <vtkPolyData.h>

#include <string>
#include <vector>

namespace cementsph::surfacemetrics {

// The per-vertex distances are stored on each surface under this point-array name (mm).
inline const char* const kDistanceArrayName = "DistanceToOtherSurface_mm";

struct DirectedDistance {
  std::size_t vertices = 0;
  double meanMm = 0.0;
  double maxMm = 0.0;
  double stdMm = 0.0; // population standard deviation
  double p95Mm = 0.0; // 95th percentile (linear interpolation between order statistics)
};

struct SurfaceComparison {
  DirectedDistance aToB; // vertices of a, distances to surface b
  DirectedDistance bToA;
  double errorMm = 0.0;         // max(aToB.mean, bToA.mean): the paper's error
  std::string errorDirection;   // "a_to_b" or "b_to_a", whichever gave the error
  double hausdorffMm = 0.0;     // max of the two directed maxima
  double hausdorff95Mm = 0.0;   // max of the two directed 95th percentiles
};

// Distances from each vertex of `from` to the surface (triangles) of `to`, in mm.
std::vector<double> vertexDistances(vtkPolyData* from, vtkPolyData* to);

DirectedDistance summarise(const std::vector<double>& distances);

// Both ways. Adds kDistanceArrayName to the point data of a and b (in place), for colouring.
// Throws std::invalid_argument if either surface has no points or no cells.
SurfaceComparison compareSurfaces(vtkPolyData* a, vtkPolyData* b);

} // namespace cementsph::surfacemetrics
