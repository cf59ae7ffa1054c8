// Three orthogonal slices through a point of a CT (axial, coronal, sagittal, in the patient frame), in a
// bone window, with the cement drawn over them: cement in bone blue, leaked cement (outside bone) red or in
// its leak class's colour. Composed pixel by pixel on the CPU, text included (VTK's FreeType rasteriser into an
// image, blended in: no OpenGL, so nothing can come back black) and written as PNG.
//
// What a planning engineer reads on it (annotate, the default):
// - each panel's plane name and position, and the patient direction each edge faces (LPS: L/R, A/P, S/I), both
//   from the CT's direction matrix;
// - a scale bar (scaleBarMm, halved until it fits the panel's width) below each panel, its length in pixels
//   scaleBarMm / (voxel spacing / pixels per voxel) along the panel's horizontal axis;
// - the cannula tip as a ring and its shaft (from the tip back along the direction) as a line, both projected
//   onto each panel's plane;
// - leaked cement in the colour of its leak class (tissueClasses, exact; or leakSites, the nearest site's kind);
// - the vertebra's outline (vertebraMask);
// - a legend of the colours the picture uses.
//
// Panel axes: the conventional views whatever order the voxels are stored in (flipped or permuted axes, as
// inject's files on the input grid may be): axial with the patient's right on the picture's left and anterior up
// (as radiologists view it), coronal with the right on the left and superior up, sagittal with anterior on the left
// and superior up. Each patient axis is the voxel axis mostly along it (nearest voxel, no resampling); an oblique CT
// whose voxel axes are near 45 degrees keeps the stored order (voxel x right, y down or z up) and its letters name
// the patient direction each edge mostly faces.
//
// Colours (RGB): cement in bone half (40, 110, 255) over the CT grey; target without cement half (255, 220, 0);
// leaked, opaque, by kind: disc (220, 0, 220), canal (255, 140, 0), venous (140, 70, 255), other_bone
// (150, 90, 30), cortex_breach and soft-tissue and any kind not listed or not known (230, 20, 20); tip ring
// (255, 255, 0); trajectory (0, 220, 255); vertebra outline (0, 200, 80); text and scale bar black on white.
#pragma once

#include <vtkImageData.h>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cementsph::rendering {

// A leak site as inject's metrics.json lists it: cement-weighted centre (mm, the CT's physical frame) and kind
// ("disc", "canal", "venous", "other_bone", "cortex_breach"; the HU rule's "soft-tissue").
struct LeakSiteMark {
  std::array<double, 3> positionMm{0, 0, 0};
  std::string kind;
};

struct CementSlicesOptions {
  double windowHu = 1500.0, levelHu = 300.0; // the bone window (W 1500, L 300)
  int pixelsPerPanel = 320;                  // each panel is scaled (nearest voxel) to about this width
  // Plane names, edge letters, scale bars and the legend; false: the bare panels side by side, 8 px apart.
  bool annotate = true;
  double scaleBarMm = 10.0; // 0: no scale bar
  int fontPx = 14;          // text height (px); the edge letters are bold
  // The cannula: tip (mm) and unit direction from the entry towards the tip. The tip is drawn as a ring on every
  // panel (its projection onto the panel's plane), the direction as the shaft from the tip back to the panel's
  // edge (nothing where the shaft is normal to the panel).
  std::optional<std::array<double, 3>> tipMm;
  std::optional<std::array<double, 3>> directionUnit;
  // Leak classes. tissueClasses: a map on the CT's grid of anatomy::TissueClass codes (VertebraAnatomy.h); each
  // leaked voxel takes its own voxel's leak kind (anatomy::leakKind). Otherwise leakSites: each leaked voxel takes
  // the kind of the site whose centre is nearest (sites are 26-connected, so this is exact for sites apart and
  // approximate where sites of two kinds touch). Neither: every leak red, "leaked".
  vtkImageData* tissueClasses = nullptr;
  std::vector<LeakSiteMark> leakSites;
  // The vertebra's outline: a label map on the CT's grid; the vertebra is the voxels equal to vertebraLabel, or
  // with vertebraLabel < 0, equal to the (non-zero) label under the tip, or without a tip (or zero there) every
  // non-zero voxel. A binary mask and a TotalSegmentator map both work.
  vtkImageData* vertebraMask = nullptr;
  int vertebraLabel = -1;
};

// What one injection draws on its slices, the same for inject's cement_slices.png and plan's best/: the cannula
// (tip ring and shaft), each leak site in its class's colour (with its volume, which picks the slices' centre)
// and, where known, the vertebra (a label map on the CT's grid: --labels, or the bone rule's anatomy_labels.nrrd
// with its target_vertebra class 1).
struct InjectionMarks {
  std::array<double, 3> tipMm{0, 0, 0};
  std::array<double, 3> direction{0, 0, 1}; // from the entry towards the tip, any length
  struct Leak {
    LeakSiteMark site;
    double volumeMl = 0;
  };
  std::vector<Leak> leaks;
  vtkImageData* vertebraMask = nullptr;
  int vertebraLabel = -1;
  // `base` with the cannula, the leak sites and the vertebra set.
  CementSlicesOptions options(CementSlicesOptions base = {}) const;
  // Where inject's slices cross: the largest leak's centre (the leak a surgeon must see), else the tip.
  std::array<double, 3> centreMm() const;
};

// ct: scalar HU image; labels: the same grid, 0 no cement, 1 cement in bone, 2 leaked cement (as
// cement_labels.nrrd), 3 a target region without cement (yellow; `cementsph plan`). centreMm: the slices'
// crossing point in the CT's physical frame (mm; the voxel axes run along the patient axes, possibly permuted
// or mirrored, as inject writes them). Throws std::invalid_argument for images of different grids, a centre
// outside, a non-finite tip, a zero or non-finite direction, or a negative or non-finite scaleBarMm;
// std::runtime_error when the PNG cannot be written (none is left).
void writeCementSlices(vtkImageData* ct, vtkImageData* labels, const std::array<double, 3>& centreMm,
                       const std::filesystem::path& png, const CementSlicesOptions& options = {});

} // namespace cementsph::rendering
