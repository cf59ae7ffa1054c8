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

// z range (mm) of voxels >= threshold; widens `lo`/`hi`.
void thresholdZRange(vtkImageData* v, double threshold, double& lo, double& hi) {
  if (isEmpty(v)) return;
  int d[3];
  v->GetDimensions(d);
  double origin[3], spacing[3];
  v->GetOrigin(origin);
  v->GetSpacing(spacing);
  vtkDataArray* s = v->GetPointData()->GetScalars();
  const vtkIdType plane = static_cast<vtkIdType>(d[0]) * d[1];
  for (int k = 0; k < d[2]; ++k) {
    for (vtkIdType p = 0; p < plane; ++p) {
      if (s->GetComponent(k * plane + p, 0) >= threshold) {
        const double z = origin[2] + k * spacing[2];
        lo = std::min(lo, z);
        hi = std::max(hi, z);
        break;
      }
    }
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
  int nx = 0, ny = 0;
  for (vtkImageData* v : rows) {
    int d[3];
    v->GetDimensions(d);
    nx = std::max(nx, d[0]);
    ny = std::max(ny, d[1]);
  }
  int scale = options.pixelScale;
  if (scale <= 0) scale = std::max(1, (160 + nx - 1) / nx);
  if (!(options.scaleBarMm >= 0.0) || !std::isfinite(options.scaleBarMm))
    throw std::invalid_argument("renderSliceComparison: the scale bar's length must be a finite number of mm >= 0");
  const int gap = std::max(0, options.gapPx);
  const int panelW = nx * scale, panelH = ny * scale;
  // Each panel sits in its labels' margins (none without annotate), the cells gap px apart.
  const detail::PanelMargins m =
      options.annotate ? detail::annotationMargins(options.fontPx) : detail::PanelMargins{};
  const int cellW = m.left + panelW + m.right, cellH = m.top + panelH + m.bottom;
  const int width = gap + static_cast<int>(z.size()) * (cellW + gap);
  const int height = gap + static_cast<int>(rows.size()) * (cellH + gap);
  if (width > 16384 || height > 16384)
    throw std::invalid_argument("renderSliceComparison: picture of " + std::to_string(width) + " x " +
                                std::to_string(height) + " px is too large; lower pixelScale or maxSlices");

  detail::PixelCanvas canvas(width, height, {255, 255, 255});
  const double span = options.windowHighHU - options.windowLowHU;
  const char* const rowNames[2] = {"post-op CT", "simulated CT"};
  for (std::size_t r = 0; r < rows.size(); ++r) {
    vtkImageData* v = rows[r];
    int d[3];
    double origin[3], spacing[3], direction[9];
    v->GetDimensions(d);
    v->GetOrigin(origin);
    v->GetSpacing(spacing);
    std::copy_n(v->GetDirectionMatrix()->GetData(), 9, direction);
    vtkDataArray* s = v->GetPointData()->GetScalars();
    const vtkIdType plane = static_cast<vtkIdType>(d[0]) * d[1];
    const int top = gap + static_cast<int>(r) * (cellH + gap) + m.top;
    for (std::size_t c = 0; c < z.size(); ++c) {
      const int leftPx = gap + static_cast<int>(c) * (cellW + gap) + m.left;
      const long k = std::lround((z[c] - origin[2]) / spacing[2]);
      const bool inside = k >= 0 && k < d[2];
      for (int j = 0; j < panelH; ++j) {
        for (int i = 0; i < panelW; ++i) {
          const int vi = i / scale, vj = j / scale; // voxel column / row; row vj = y index, drawn downwards
          unsigned char grey = 0;
          if (inside && vi < d[0] && vj < d[1]) {
            const double hu = s->GetComponent(k * plane + static_cast<vtkIdType>(vj) * d[0] + vi, 0);
            // NaN (e.g. outside a resampled field of view) shows as black, like air.
            const double t = std::isnan(hu) ? 0.0 : std::clamp((hu - options.windowLowHU) / span, 0.0, 1.0);
            grey = static_cast<unsigned char>(std::lround(255.0 * t));
          }
          canvas.set(leftPx + i, top + j, {grey, grey, grey});
        }
      }
      if (!options.annotate) continue;
      // Voxel x runs to the right, y downwards; the letters say where they run in the patient.
      detail::PanelAnnotation a;
      std::ostringstream title;
      title << rowNames[r] << ", " << detail::planeName(direction, 2) << " z = " << std::fixed << std::setprecision(1)
            << z[c] << " mm";
      a.title = title.str();
      a.left = detail::patientLetter(direction, 0, -1);
      a.right = detail::patientLetter(direction, 0, +1);
      a.top = detail::patientLetter(direction, 1, -1);
      a.bottom = detail::patientLetter(direction, 1, +1);
      a.mmPerPixel = spacing[0] / scale;
      a.scaleBarMm = options.scaleBarMm;
      detail::annotatePanel(canvas, leftPx, top, panelW, panelH, a, options.fontPx);
    }
  }
  // RGB although the slices are grey: viewers and the project's PNG checks treat 3 channels uniformly.
  const auto image = canvas.toImage();
  writePngAtomically(image, png);
}

} // namespace cementsph::rendering
