#include "cementsph/drr/XraySequence.h"

#include "cementsph/drr/AttenuationVolume.h"
#include "cementsph/drr/ProjectVolume.h"
#include "cementsph/drr/vtkDRRFilter.h"

#include <vtkDataArray.h>
#include <vtkPointData.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace cementsph::drr {

namespace {

// Labels the 8-connected regions of mask (cols x rows, j = 0 the bottom row): labels[p] = 0 outside the
// mask, 1, 2, ... for the regions in scan order. Returns the number of regions.
std::size_t labelRegions(std::vector<int>& labels, const unsigned char* mask, int cols, int rows) {
  labels.assign(static_cast<std::size_t>(cols) * rows, 0);
  std::size_t regions = 0;
  std::vector<int> stack;
  for (int start = 0; start < cols * rows; ++start) {
    if (!mask[start] || labels[start]) continue;
    const int label = static_cast<int>(++regions);
    labels[start] = label;
    stack.assign(1, start);
    while (!stack.empty()) {
      const int p = stack.back();
      stack.pop_back();
      const int i = p % cols, j = p / cols;
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const int ii = i + di, jj = j + dj;
          if (ii < 0 || jj < 0 || ii >= cols || jj >= rows) continue;
          const int q = jj * cols + ii;
          if (mask[q] && !labels[q]) {
            labels[q] = label;
            stack.push_back(q);
          }
        }
    }
  }
  return regions;
}

} // namespace

double XraySequence::drrPerWaterMm() { return AttenuationVolume::kMuWaterPerMm * vtkDRRFilter::kPixelScale; }

XraySequence::XraySequence(const XraySequenceOptions& options) : options_(options) {
  if (const std::string problem = options.geometry.validate(); !problem.empty()) throw std::invalid_argument(problem);
  if (!(options.cementThresholdWaterMm > 0.0) || !std::isfinite(options.cementThresholdWaterMm))
    throw std::invalid_argument("the cement threshold must be a positive number of mm of water (got " +
                                std::to_string(options.cementThresholdWaterMm) + ")");
  if (options.threads < 0) throw std::invalid_argument("the number of threads must be 0 or more");
  if (options.injectionPointMm) {
    for (double c : *options.injectionPointMm)
      if (!std::isfinite(c)) throw std::invalid_argument("the injection point must be finite");
    if (!(options.injectionSearchRadiusMm >= 0.0))
      throw std::invalid_argument("the injection search radius must be 0 mm or more");
  }
}

double XraySequence::thresholdDrr() const { return options_.cementThresholdWaterMm * drrPerWaterMm(); }

void XraySequence::addFrame(double timeS, vtkImageData* volumeHU) {
  if (!std::isfinite(timeS)) throw std::invalid_argument("frame time is not a finite number of seconds");
  if (!frames_.empty() && !(timeS > frames_.back().timeS))
    throw std::invalid_argument("frame times must increase (" + std::to_string(timeS) + " s after " +
                                std::to_string(frames_.back().timeS) + " s)");
  if (volumeHU == nullptr || volumeHU->GetPointData()->GetScalars() == nullptr)
    throw std::invalid_argument("the frame volume has no voxel values");

  XrayFrame frame;
  frame.timeS = timeS;
  frame.drr = projectVolume(volumeHU, options_.geometry, options_.threads);
  const auto* pixels = static_cast<const float*>(frame.drr->GetScalarPointer());
  const std::size_t n = static_cast<std::size_t>(options_.geometry.rows) * options_.geometry.cols;
  frame.cementMask = vtkSmartPointer<vtkImageData>::New();
  frame.cementMask->CopyStructure(frame.drr);
  frame.cementMask->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  frame.cementMask->GetPointData()->GetScalars()->SetName("cement");
  auto* mask = static_cast<unsigned char*>(frame.cementMask->GetScalarPointer());
  // Frame 0 is the background: nothing has been added to it, so its mask is empty by definition.
  const float* background = frames_.empty() ? pixels : static_cast<const float*>(frames_[0].drr->GetScalarPointer());
  const double threshold = thresholdDrr();
  for (std::size_t p = 0; p < n; ++p)
    mask[p] = static_cast<double>(pixels[p]) - static_cast<double>(background[p]) > threshold ? 1 : 0;
  const DRRGeometry& g = options_.geometry;
  std::vector<int> labels;
  frame.regionsAboveThreshold = labelRegions(labels, mask, g.cols, g.rows);
  if (options_.injectionPointMm && frame.regionsAboveThreshold > 0) {
    // The region at the point's projection, else the nearest pixel's region within the search radius.
    const auto ij = g.project(*options_.injectionPointMm);
    const double m = g.isocentreMagnification();
    int keep = 0;
    double best = std::numeric_limits<double>::infinity();
    for (int j = 0; j < g.rows; ++j)
      for (int i = 0; i < g.cols; ++i) {
        const int label = labels[static_cast<std::size_t>(j) * g.cols + i];
        if (!label) continue;
        // Distance in the isocentre plane from the projected point to the pixel's square (0 inside it).
        const double du = std::max(0.0, std::abs(i - ij[0]) - 0.5) * g.pixelWidthMm() / m;
        const double dv = std::max(0.0, std::abs(j - ij[1]) - 0.5) * g.pixelHeightMm() / m;
        const double d = std::hypot(du, dv);
        if (d < best) best = d, keep = label;
      }
    if (best > options_.injectionSearchRadiusMm) keep = 0;
    for (std::size_t p = 0; p < n; ++p) mask[p] = labels[p] == keep && keep != 0 ? 1 : 0;
  }
  for (std::size_t p = 0; p < n; ++p) frame.cementPixels += mask[p];
  frame.detectorAreaMm2 = static_cast<double>(frame.cementPixels) * g.pixelWidthMm() * g.pixelHeightMm();
  const double m = g.isocentreMagnification();
  frame.projectedAreaMm2 = frame.detectorAreaMm2 / (m * m);
  frames_.push_back(std::move(frame));
}

} // namespace cementsph::drr
