#include "cementsph/drr/XraySequence.h"

#include "cementsph/drr/AttenuationVolume.h"
#include "cementsph/drr/ProjectVolume.h"
#include "cementsph/drr/vtkDRRFilter.h"

#include <vtkDataArray.h>
#include <vtkPointData.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace cementsph::drr {

double XraySequence::drrPerWaterMm() { return AttenuationVolume::kMuWaterPerMm * vtkDRRFilter::kPixelScale; }

XraySequence::XraySequence(const XraySequenceOptions& options) : options_(options) {
  if (const std::string problem = options.geometry.validate(); !problem.empty()) throw std::invalid_argument(problem);
  if (!(options.cementThresholdWaterMm > 0.0) || !std::isfinite(options.cementThresholdWaterMm))
    throw std::invalid_argument("the cement threshold must be a positive number of mm of water (got " +
                                std::to_string(options.cementThresholdWaterMm) + ")");
  if (options.threads < 0) throw std::invalid_argument("the number of threads must be 0 or more");
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
  for (std::size_t p = 0; p < n; ++p) {
    mask[p] = static_cast<double>(pixels[p]) - static_cast<double>(background[p]) > threshold ? 1 : 0;
    frame.cementPixels += mask[p];
  }
  const DRRGeometry& g = options_.geometry;
  frame.detectorAreaMm2 = static_cast<double>(frame.cementPixels) * g.pixelWidthMm() * g.pixelHeightMm();
  const double m = g.isocentreMagnification();
  frame.projectedAreaMm2 = frame.detectorAreaMm2 / (m * m);
  frames_.push_back(std::move(frame));
}

} // namespace cementsph::drr
