// Affine, intensity-based registration of a post-injection CT onto the pre-injection CT
// (ITK v4 framework): a translation stage, a rigid stage, then an affine stage, each
// multi-resolution, with a
// same-modality metric (mean squares: both scans are CT of the same specimen, in HU).
//
// Robustness to the cement: the cement exists only in the moving (post) image and is brighter than
// anything in the fixed (pre) image. Moving voxels above max(fixed) + margin, dilated to cover their
// partial-volume rim, are masked out of the metric, so the cement cannot pull the result.
#pragma once

#include "cementsph/imaging/ImageTypes.h"

#include <itkAffineTransform.h>

#include <string>
#include <vector>

namespace cementsph::imaging {

using AffineTransformType = itk::AffineTransform<double, 3>;

struct RegistrationOptions {
  bool maskCement = true;
  double cementMarginHU = 100.0;    // cement = moving > max(fixed) + margin
  double cementDilationMm = 2.0;    // grows the cement mask over its partial-volume rim
  // The metric samples only the specimen: fixed voxels above this (tissue, not air), grown by
  // bodyMarginMm. Skipped when that is over 90 % of the volume; -infinity or NaN disables it.
  double bodyThresholdHU = -500.0;
  double bodyMarginMm = 3.0;
  // Multi-resolution schedules (shrink factors; Gaussian sigmas in voxels of the shrunk level).
  std::vector<unsigned> translationShrink{4};
  std::vector<double> translationSigmaVoxels{2.0};
  std::vector<unsigned> rigidShrink{4, 2}; // empty: no rigid stage
  std::vector<double> rigidSigmaVoxels{2.0, 1.0};
  std::vector<unsigned> affineShrink{2, 1};
  std::vector<double> affineSigmaVoxels{1.0, 0.0};
  unsigned maxIterationsPerLevel = 200;
  double initialStepMm = 2.0;       // line-search bracket: 2x this largest voxel shift
  double convergenceValue = 1e-5;   // ITK's windowed convergence test on the metric
  unsigned convergenceWindow = 10;
  unsigned lineSearchIterations = 10; // golden-section evaluations per iteration, at most
  unsigned samplesPerLevel = 5000;  // random samples on the specimen per level (fixed seed)
  bool verbose = false;
};

struct RegistrationLevel {
  std::string stage; // "translation", "rigid" or "affine"
  unsigned level = 0;
  unsigned shrink = 1;
  unsigned iterations = 0;
  double metric = 0.0; // mean squares, HU^2, at the end of the level
  double seconds = 0.0; // wall time from the level's start (after smoothing) to its last iteration
  std::string stopCondition;
};

struct RegistrationResult {
  AffineTransformType::Pointer transform; // maps fixed (pre) points to moving (post) points, mm
  double finalMetric = 0.0;
  std::vector<RegistrationLevel> levels;
  double cementThresholdHU = 0.0;
  std::size_t maskedMovingVoxels = 0;
  double seconds = 0.0;
};

// The moving scan's metric mask as registerAffine makes it (options.maskCement): 0 on the cement (moving voxels
// at least the fixed scan's maximum + options.cementMarginHU, grown by a ball of options.cementDilationMm),
// 1 elsewhere, on the moving scan's grid. masked: the cement voxels (0 = nothing to mask: the mask is all 1).
// imaging-bench hands elastix the same mask, so that the two registrations look at the same voxels.
MaskType::Pointer cementMetricMask(const ImageType* fixed, const ImageType* moving, const RegistrationOptions& options,
                                   std::size_t& masked);

// Throws std::runtime_error when the two volumes do not overlap in physical space.
RegistrationResult registerAffine(const ImageType* fixed, const ImageType* moving,
                                  const RegistrationOptions& options = {});

// The moving image resampled onto the fixed image's grid (linear interpolation); outside voxels get
// outsideValue (air, by default).
ImageType::Pointer resampleOnto(const ImageType* moving, const ImageType* fixedGrid,
                                const itk::Transform<double, 3, 3>* transform,
                                float outsideValue = -1024.0f);

// ITK transform files (.tfm/.txt, .h5, .mat), written atomically.
void writeTransform(const AffineTransformType* transform, const std::string& path);
AffineTransformType::Pointer readTransform(const std::string& path);

} // namespace cementsph::imaging

namespace cementsph::imaging {

// A short text table of the levels (stage, shrink, iterations, metric) and the final metric, for
// the command-line summaries.
std::string formatRegistrationReport(const RegistrationResult& result);

} // namespace cementsph::imaging
