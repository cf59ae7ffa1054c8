// Three orthogonal slices through a point of a CT (axial, coronal, sagittal, in the patient frame), in a
// bone window, with the cement drawn over them: cement in bone blue, leaked cement (outside bone) red.
// Composed pixel by pixel on the CPU (no OpenGL: nothing can come back black) and written as PNG.
#pragma once

#include <vtkImageData.h>

#include <array>
#include <filesystem>

namespace cementsph::rendering {

struct CementSlicesOptions {
  double windowHu = 1500.0, levelHu = 300.0; // the bone window (W 1500, L 300)
  int pixelsPerPanel = 320;                  // each panel is scaled (nearest voxel) to about this width
};

// ct: scalar HU image; labels: the same grid, 0 no cement, 1 cement in bone, 2 leaked cement (as
// cement_labels.nrrd), 3 a target region without cement (yellow; `cementsph plan`). centreMm: the slices' crossing point in the images' physical frame (axis-aligned
// images). Throws std::invalid_argument for images of different grids or a centre outside, std::runtime_error
// when the PNG cannot be written (none is left).
void writeCementSlices(vtkImageData* ct, vtkImageData* labels, const std::array<double, 3>& centreMm,
                       const std::filesystem::path& png, const CementSlicesOptions& options = {});

} // namespace cementsph::rendering
