// The paper's Fig. 12 (Basafa et al. 2013): X-ray frames of the injection over time, simulation above
// experiment, the cement outlined in each. One row per sequence (simulation; reference when there is one),
// one column per instant, labelled with its time. The DRRs are drawn as a C-arm monitor shows them, dense
// matter dark: grey = 255 (1 - value / windowMax), clamped; each row has one window, so the frames of a row
// compare directly. The segmented cement's outline is drawn in the row's colour (1 px, the mask's boundary
// at panel resolution); a column without a frame in a row is a light blue-grey panel. Pure pixel work written with vtkPNGWriter (text by VTK's FreeType, which needs no
// GL): no render window, no display, the same bytes on every machine with the same fonts.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

class vtkImageData;

namespace cementsph::rendering {

struct XrayPanel {
  vtkImageData* drr = nullptr;  // 2-D float (any numeric type) image, spacing = pixel size; null: no frame
  vtkImageData* mask = nullptr; // same grid, non-zero = cement; null: no outline
};

struct XrayFramesRow {
  std::string label;                      // drawn left of the row, e.g. "simulation"
  std::vector<XrayPanel> panels;          // one per column
  std::array<unsigned char, 3> outlineRgb{0, 110, 255};
  double windowMax = 0.0;                 // DRR value drawn black; 0: the largest pixel of the row's panels
};

struct XrayFramesOptions {
  int panelWidthPx = 200; // each DRR is resampled (nearest pixel) to this width; height keeps the aspect
  int gapPx = 6;
  int fontSizePx = 15;    // labels; 0: no labels
};

// Writes the picture atomically. Throws std::invalid_argument for no rows, rows of different lengths, a
// column-label count that differs from the panel count, a panel whose mask is not on its DRR's grid,
// panels of different physical aspect in one picture, or no drawable panel at all; std::runtime_error if
// the file cannot be written.
void renderXrayFrames(const std::vector<XrayFramesRow>& rows, const std::vector<std::string>& columnLabels,
                      const std::filesystem::path& png, const XrayFramesOptions& options = {});

} // namespace cementsph::rendering
