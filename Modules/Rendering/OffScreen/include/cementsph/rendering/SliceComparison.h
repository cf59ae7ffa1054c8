// The paper's Fig. 11 (Basafa et al. 2013): axial CT slices every few millimetres through the cement,
// post-operative CT in the top row, simulated CT in the bottom row, both in the same HU window.
// Pure pixel work on vtkImageData written with vtkPNGWriter: no render window, no display, no GL, so the
// picture is exactly reproducible and works anywhere.
#pragma once

#include <filesystem>
#include <optional>
#include <utility>
#include <vector>

class vtkImageData;

namespace cementsph::rendering {

struct SliceComparisonOptions {
  // HU mapped to black and white (linear in between, clamped): shows bone and cement together.
  double windowLowHU = -200.0, windowHighHU = 2000.0;
  // Range of z (mm, patient space) holding the cement. Empty: the z range of the voxels of either volume
  // at or above cementThresholdHU.
  std::optional<std::pair<double, double>> zRangeMm;
  double cementThresholdHU = 1500.0;
  // At most this many slices (the central ones are kept when the cement spans more).
  int maxSlices = 12;
  // Each voxel becomes a pixelScale x pixelScale block; 0: the smallest integer that makes a panel at
  // least 160 px wide (small volumes would otherwise give thumbnails).
  int pixelScale = 0;
  int gapPx = 6; // white gap between panels and around the picture
  // Issue 20, item 6: each panel's title (row and plane: "post-op CT  axial z = 5.0 mm"), the patient direction
  // each edge faces (L/R, A/P from the volume's direction matrix, so a CT stored mirrored gets its letters on the
  // other side) and a scale bar of scaleBarMm (halved until it fits) below it, its length scaleBarMm / (x spacing /
  // pixelScale) px. Text is rasterised on the CPU (FreeType), like the panels. false: the bare panels.
  bool annotate = true;
  double scaleBarMm = 10.0; // 0: no bar
  int fontPx = 12;
  // The first row's name in its titles: what the post-injection scan is (study::postScanLabel).
  std::string postRowName = "post-op CT";
};

// The z positions (mm) of the slices renderSliceComparison() draws: spacingMm apart, centred on the
// cement's z range, at least one. Exposed so callers and tests can label or check them.
std::vector<double> slicePositionsMm(vtkImageData* postCT, vtkImageData* simulatedCT, double spacingMm,
                                     const SliceComparisonOptions& options = {});

// Writes a PNG with one column per slice: row 1 postCT, row 2 simulatedCT (omitted when simulatedCT is
// null), each panel in its labels' margins when annotate is set. Each slice is the nearest voxel plane to
// the patient z position in each volume (no interpolation); a position outside a volume gives a black
// panel. Each panel is the conventional axial view however the volume is stored: the patient's right on
// the left, anterior up (LPS x to the right, y down), each patient axis the voxel axis mostly along it
// (flipped and permuted grids look the same; an oblique grid near 45 degrees keeps its stored order, voxel
// x right and y down, and its letters name where those run).
// Throws std::invalid_argument for a null/empty postCT, spacingMm <= 0, an empty HU window, no voxel
// at or above the cement threshold (when zRangeMm is empty), or a negative or non-finite scaleBarMm;
// std::runtime_error if the file cannot be written. The file is written atomically.
void renderSliceComparison(vtkImageData* postCT, vtkImageData* simulatedCT, const std::filesystem::path& png,
                           double spacingMm = 5.0, const SliceComparisonOptions& options = {});

} // namespace cementsph::rendering
