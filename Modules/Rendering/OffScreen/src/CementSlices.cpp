#include "cementsph/rendering/CementSlices.h"

#include "cementsph/rendering/OffScreenWindow.h"

#include <vtkSmartPointer.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cementsph::rendering {

void writeCementSlices(vtkImageData* ct, vtkImageData* labels, const std::array<double, 3>& centreMm,
                       const std::filesystem::path& png, const CementSlicesOptions& o) {
  if (!ct || !labels) throw std::invalid_argument("cement slices: no image");
  int dims[3], ldims[3];
  ct->GetDimensions(dims);
  labels->GetDimensions(ldims);
  if (dims[0] != ldims[0] || dims[1] != ldims[1] || dims[2] != ldims[2])
    throw std::invalid_argument("cement slices: the CT and the labels have different grids");
  double origin[3], spacing[3];
  ct->GetOrigin(origin);
  ct->GetSpacing(spacing);
  int centre[3];
  for (int a = 0; a < 3; ++a) {
    centre[a] = int(std::lround((centreMm[std::size_t(a)] - origin[a]) / spacing[a]));
    if (centre[a] < 0 || centre[a] >= dims[a]) throw std::invalid_argument("cement slices: the centre is outside the CT");
  }
  // Panels: axial (x right, y down: z fixed), coronal (x, z up: y fixed), sagittal (y, z up: x fixed).
  struct Panel { int u, v, fixed; bool flipV; };
  const Panel panels[3] = {{0, 1, 2, false}, {0, 2, 1, true}, {1, 2, 0, true}};
  int scale[3], widths[3], heights[3];
  int total = 0, height = 0;
  for (int p = 0; p < 3; ++p) {
    const Panel& q = panels[p];
    // Square pixels in mm: the scale per voxel follows each axis' spacing.
    const double mmPerPixel = std::max(dims[q.u] * spacing[q.u], 1e-9) / o.pixelsPerPanel;
    scale[p] = std::max(1, int(std::lround(spacing[q.u] / mmPerPixel)));
    widths[p] = dims[q.u] * scale[p];
    heights[p] = int(std::lround(dims[q.v] * spacing[q.v] / spacing[q.u])) * scale[p];
    total += widths[p] + (p ? 8 : 0);
    height = std::max(height, heights[p]);
  }
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(total, height, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* out = static_cast<unsigned char*>(image->GetScalarPointer());
  std::fill(out, out + std::size_t(total) * std::size_t(height) * 3, 255);
  int x0 = 0;
  for (int p = 0; p < 3; ++p) {
    const Panel& q = panels[p];
    for (int py = 0; py < heights[p]; ++py)
      for (int px = 0; px < widths[p]; ++px) {
        int ijk[3];
        ijk[q.fixed] = centre[q.fixed];
        ijk[q.u] = std::min(dims[q.u] - 1, px / scale[p]);
        const double along = double(py) / heights[p] * dims[q.v];
        ijk[q.v] = std::min(dims[q.v] - 1, int(along));
        if (!q.flipV) ijk[q.v] = dims[q.v] - 1 - ijk[q.v]; // VTK's image rows go up: keep +y (posterior) down
        const double hu = ct->GetScalarComponentAsDouble(ijk[0], ijk[1], ijk[2], 0);
        const int label = int(labels->GetScalarComponentAsDouble(ijk[0], ijk[1], ijk[2], 0));
        const double g = std::clamp((hu - (o.levelHu - 0.5 * o.windowHu)) / o.windowHu, 0.0, 1.0) * 255.0;
        double rgb[3] = {g, g, g};
        if (label == 1) { // cement in bone: blue, half over the CT
          rgb[0] = 0.5 * g + 0.5 * 40;
          rgb[1] = 0.5 * g + 0.5 * 110;
          rgb[2] = 0.5 * g + 0.5 * 255;
        } else if (label == 3) { // a target without cement: yellow, half over the CT
          rgb[0] = 0.5 * g + 0.5 * 255;
          rgb[1] = 0.5 * g + 0.5 * 220;
          rgb[2] = 0.5 * g + 0.5 * 0;
        } else if (label == 2) { // leaked: red, opaque
          rgb[0] = 230;
          rgb[1] = 20;
          rgb[2] = 20;
        }
        unsigned char* pixel = out + 3 * (std::size_t(py) * std::size_t(total) + std::size_t(x0 + px));
        for (int c = 0; c < 3; ++c) pixel[c] = static_cast<unsigned char>(std::lround(rgb[c]));
      }
    x0 += widths[p] + 8;
  }
  writeImagePng(image, png);
}

} // namespace cementsph::rendering
