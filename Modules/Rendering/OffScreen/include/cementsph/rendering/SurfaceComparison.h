// The paper's Fig. 7 (Basafa et al. 2013): the cement isosurface from the post-operative CT next to the
// simulated one, seen from the same camera, and the simulated surface coloured by its distance to the
// experimental surface. Drawn off-screen (makeOffScreenRenderWindow), so it works on headless machines.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

class vtkImageData;
class vtkPolyData;

namespace cementsph::rendering {

struct SurfaceComparisonOptions {
  // The whole picture; the three panels share the width equally.
  int widthPx = 1500, heightPx = 560;
  // Point array of `simulation` used for the third panel (cementsph::surfacemetrics::compareSurfaces
  // stores the per-vertex distances under this name).
  std::string distanceArray = "DistanceToOtherSurface_mm";
  // Upper end of the colour scale, mm; empty: the array's maximum. Fixing it makes pictures of
  // different runs comparable.
  std::optional<double> maxDistanceMm;
  // The simulation's label map (cement_labels.nrrd of `inject`: 1 cement in bone, 2 leaked), not owned; when
  // given, the middle panel draws each vertex of the simulated surface in the colour of the nearest cement
  // voxel within one voxel (blue in bone, red leaked; blue where none is that near) and its title says so.
  vtkImageData* simulationLabels = nullptr;
  // The left panel's title: what the post-injection scan is (study::postScanLabel: "post (CT)", or
  // "post (phantom, simulated)" for a scan the phantom made).
  std::string postTitle = "post (CT)";
  // Camera direction (from the focal point towards the camera) and view-up, patient axes.
  double viewDirection[3] = {0.55, -1.0, 0.45};
  double viewUp[3] = {0.0, 0.0, 1.0};
};

// Writes one PNG with three panels: experiment (left), simulation (middle), and simulation coloured by
// options.distanceArray with a scalar bar in mm (right). One camera, fitted to the union of both
// surfaces' bounds, is shared by all panels so sizes and positions compare directly.
// Throws std::invalid_argument if a surface is null or empty, or the distance array is missing or not
// one component; std::runtime_error if rendering or writing fails. The file is written atomically.
void renderSurfaceComparison(vtkPolyData* experiment, vtkPolyData* simulation, const std::filesystem::path& png,
                             const SurfaceComparisonOptions& options = {});

} // namespace cementsph::rendering
