// Fig. 11 style slice pictures. The pixels are computed directly from the voxels (nearest plane, linear
// HU window) instead of going through vtkImageReslice + a render window: no GL means the same bytes on
// every machine, so the test can compare exactly, and the picture needs no display at all.
#include "cementsph/rendering/SliceComparison.h"
#include "PixelCanvas.h"
#include "cementsph/rendering/OffScreenWindow.h"

#include <vtkImageData.h>
#include <vtkDataArray.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace cementsph::rendering {

namespace {

bool isEmpty(vtkImageData* v) {
  if (v == nullptr || v->GetPointData()->GetScalars() == nullptr) return true;
  int d[3];
  v->GetDimensions(d);
  return d[0] < 1 || d[1] < 1 || d[2] < 1;
}

// The patient z (mm) of voxel (i, j, k): origin + direction (i sx, j sy, k sz), its z component.
double patientZ(vtkImageData* v, int i, int j, int k) {
  double p[3];
  v->TransformIndexToPhysicalPoint(i, j, k, p);
  return p[2];
}

// z range (mm, patient frame) of voxels >= threshold; widens `lo`/`hi`.
void thresholdZRange(vtkImageData* v, double threshold, double& lo, double& hi) {
  if (isEmpty(v)) return;
  int d[3];
  v->GetDimensions(d);
  vtkDataArray* s = v->GetPointData()->GetScalars();
  vtkIdType n = 0;
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i, ++n)
        if (s->GetComponent(n, 0) >= threshold) {
          const double z = patientZ(v, i, j, k);
          lo = std::min(lo, z);
          hi = std::max(hi, z);
        }
}

void writePngAtomically(vtkImageData* image, const std::filesystem::path& png) {
  if (png.filename().empty()) throw std::invalid_argument("renderSliceComparison: '" + png.string() + "' names no file");
  const std::filesystem::path folder = png.parent_path().empty() ? "." : png.parent_path();
  if (!std::filesystem::is_directory(folder))
    throw std::runtime_error("cannot write " + png.string() + ": folder " + folder.string() + " does not exist");
  writeImagePng(image, png); // atomic: temporary sibling, then rename
}

} // namespace

std::vector<double> slicePositionsMm(vtkImageData* postCT, vtkImageData* simulatedCT, double spacingMm,
                                     const SliceComparisonOptions& options) {
  if (isEmpty(postCT)) throw std::invalid_argument("renderSliceComparison: the post-operative CT is empty");
  if (!(spacingMm > 0.0) || !std::isfinite(spacingMm))
    throw std::invalid_argument("renderSliceComparison: slice spacing must be a positive number of mm");
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  if (options.zRangeMm) {
    lo = std::min(options.zRangeMm->first, options.zRangeMm->second);
    hi = std::max(options.zRangeMm->first, options.zRangeMm->second);
    if (!std::isfinite(lo) || !std::isfinite(hi))
      throw std::invalid_argument("renderSliceComparison: the z range is not finite");
  } else {
    thresholdZRange(postCT, options.cementThresholdHU, lo, hi);
    thresholdZRange(simulatedCT, options.cementThresholdHU, lo, hi);
    if (lo > hi)
      throw std::invalid_argument("renderSliceComparison: no voxel at or above " +
                                  std::to_string(options.cementThresholdHU) + " HU (no cement to slice through)");
  }
  // Slices spacingMm apart, centred on the range, so the cement's ends get equal margins.
  int n = static_cast<int>(std::floor((hi - lo) / spacingMm + 1e-9)) + 1;
  n = std::max(1, std::min(n, std::max(1, options.maxSlices)));
  const double centre = 0.5 * (lo + hi);
  std::vector<double> z;
  for (int i = 0; i < n; ++i) z.push_back(centre + (i - 0.5 * (n - 1)) * spacingMm);
  return z;
}

void renderSliceComparison(vtkImageData* postCT, vtkImageData* simulatedCT, const std::filesystem::path& png,
                           double spacingMm, const SliceComparisonOptions& options) {
  if (!(options.windowHighHU > options.windowLowHU))
    throw std::invalid_argument("renderSliceComparison: the HU window is empty");
  if (simulatedCT != nullptr && isEmpty(simulatedCT))
    throw std::invalid_argument("renderSliceComparison: the simulated CT is empty");
  const std::vector<double> z = slicePositionsMm(postCT, simulatedCT, spacingMm, options);

  std::vector<vtkImageData*> rows{postCT};
  if (simulatedCT != nullptr) rows.push_back(simulatedCT);
  // Each volume in the conventional axial view however it is stored: the patient's right on the left, anterior up.
  std::vector<detail::PanelAxes> views;
  int nx = 0, ny = 0;
  for (vtkImageData* v : rows) {
    int d[3];
    v->GetDimensions(d);
    double direction[9];
    std::copy_n(v->GetDirectionMatrix()->GetData(), 9, direction);
    views.push_back(detail::conventionalViews(direction)[0]);
    nx = std::max(nx, d[views.back().u]);
    ny = std::max(ny, d[views.back().v]);
  }
  int scale = options.pixelScale;
  if (scale <= 0) scale = std::max(1, (160 + nx - 1) / nx);
  if (!(options.scaleBarMm >= 0.0) || !std::isfinite(options.scaleBarMm))
    throw std::invalid_argument("renderSliceComparison: the scale bar's length must be a finite number of mm >= 0");
  const int gap = std::max(0, options.gapPx);
  const int panelW = nx * scale, panelH = ny * scale;
  // Each panel sits in its labels' margins (none without annotate), the cells gap px apart.
  detail::PanelMargins m =
      options.annotate ? detail::annotationMargins(options.fontPx) : detail::PanelMargins{};
  const std::string rowNames[2] = {options.postRowName, "simulated CT"};
  // Each panel's title ("post (phantom, simulated), axial z = 16.9 mm") can be wider than a small volume's panel:
  // the right margin grows to the widest title and a 16 px gap before the next, so no title is cut or runs on.
  auto titleOf = [&](std::size_t r, double zMm) {
    double direction[9];
    std::copy_n(rows[r]->GetDirectionMatrix()->GetData(), 9, direction);
    std::ostringstream title;
    title << rowNames[r] << ", " << detail::planeName(direction, views[r].fixed) << " z = " << std::fixed
          << std::setprecision(1) << zMm << " mm";
    return title.str();
  };
  if (options.annotate)
    for (std::size_t r = 0; r < rows.size(); ++r)
      for (double zMm : z) m.right = std::max(m.right, detail::PixelCanvas::textSize(titleOf(r, zMm), options.fontPx)[0] + 16 - m.left - panelW);
  const int cellW = m.left + panelW + m.right, cellH = m.top + panelH + m.bottom;
  const int width = gap + static_cast<int>(z.size()) * (cellW + gap);
  const int height = gap + static_cast<int>(rows.size()) * (cellH + gap);
  if (width > 16384 || height > 16384)
    throw std::invalid_argument("renderSliceComparison: picture of " + std::to_string(width) + " x " +
                                std::to_string(height) + " px is too large; lower pixelScale or maxSlices");

  detail::PixelCanvas canvas(width, height, {255, 255, 255});
  const double span = options.windowHighHU - options.windowLowHU;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    vtkImageData* v = rows[r];
    const detail::PanelAxes& q = views[r];
    int d[3];
    double origin[3], spacing[3], direction[9];
    v->GetDimensions(d);
    v->GetOrigin(origin);
    v->GetSpacing(spacing);
    std::copy_n(v->GetDirectionMatrix()->GetData(), 9, direction);
    vtkDataArray* s = v->GetPointData()->GetScalars();
    // The patient z of a plane of the fixed axis: origin z + its direction's z component x spacing x index.
    const double zPerPlane = direction[2 * 3 + q.fixed] * spacing[q.fixed];
    const int top = gap + static_cast<int>(r) * (cellH + gap) + m.top;
    for (std::size_t c = 0; c < z.size(); ++c) {
      const int leftPx = gap + static_cast<int>(c) * (cellW + gap) + m.left;
      int ijk[3];
      const long plane = std::lround((z[c] - origin[2]) / zPerPlane);
      const bool inside = plane >= 0 && plane < d[q.fixed];
      ijk[q.fixed] = static_cast<int>(plane);
      for (int j = 0; j < panelH; ++j) {
        for (int i = 0; i < panelW; ++i) {
          const int right = i / scale, down = j / scale; // voxels from the panel's left and top edges
          unsigned char grey = 0;
          if (inside && right < d[q.u] && down < d[q.v]) {
            ijk[q.u] = q.uSign > 0 ? right : d[q.u] - 1 - right;
            ijk[q.v] = q.vSign > 0 ? down : d[q.v] - 1 - down;
            const double hu = s->GetComponent(ijk[0] + static_cast<vtkIdType>(d[0]) * (ijk[1] + static_cast<vtkIdType>(d[1]) * ijk[2]), 0);
            // NaN (e.g. outside a resampled field of view) shows as black, like air.
            const double t = std::isnan(hu) ? 0.0 : std::clamp((hu - options.windowLowHU) / span, 0.0, 1.0);
            grey = static_cast<unsigned char>(std::lround(255.0 * t));
          }
          canvas.set(leftPx + i, top + j, {grey, grey, grey});
        }
      }
      if (!options.annotate) continue;
      detail::PanelAnnotation a;
      a.title = titleOf(r, z[c]);
      a.titleWidthPx = cellW;
      a.left = detail::patientLetter(direction, q.u, -q.uSign);
      a.right = detail::patientLetter(direction, q.u, q.uSign);
      a.top = detail::patientLetter(direction, q.v, -q.vSign);
      a.bottom = detail::patientLetter(direction, q.v, q.vSign);
      a.mmPerPixel = spacing[q.u] / scale;
      a.scaleBarMm = options.scaleBarMm;
      detail::annotatePanel(canvas, leftPx, top, panelW, panelH, a, options.fontPx);
    }
  }
  // RGB although the slices are grey: viewers and the project's PNG checks treat 3 channels uniformly.
  const auto image = canvas.toImage();
  writePngAtomically(image, png);
}

} // namespace cementsph::rendering
