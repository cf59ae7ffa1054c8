// Cement segmentation: registered post minus pre, threshold, keep the connected component at the
// injection site (or the largest), optional morphological closing; volume in ml.
// Both volumes must share one grid (resample the post volume onto the pre grid first).
//
// The threshold, by default, is half the cement's own contrast. A CT blurs the cement's edge over a
// voxel or two (partial volume); the true boundary is where the difference has risen halfway from the
// surroundings (0 after subtraction) to the cement's plateau. A fixed low threshold takes in the shell:
// 500 HU, 22 % of a 2300 HU contrast, added 12-13 % to the volume of three pre/post pairs with known
// truth. The rule (HalfContrast):
//   1. seed: the component at the injection point (or the largest) of (post - pre) > seedThresholdHU;
//   2. contrast C = the contrastPercentile-th percentile (default 90th) of (post - pre) in that seed:
//      the cement's plateau, robust to the shell below it and to a few noisy voxels above it;
//   3. threshold = C / 2 (never below minimumThresholdHU, which stays clear of CT noise), and the
//      component is selected again at that threshold.
#pragma once

#include "cementsph/imaging/ImageTypes.h"

#include <optional>
#include <string>

namespace cementsph::imaging {

struct SegmentationOptions {
  // Set: this fixed threshold on (post - pre), HU (the old rule was a fixed 500 HU). Unset: half the
  // cement's own contrast (see above).
  std::optional<double> differenceThresholdHU;
  // Cement raises HU by ~1000-3000 over marrow and trabecular bone; 500 HU keeps the seed clear of CT
  // noise and of the partial-volume differences left at bone edges by a sub-voxel registration error.
  double seedThresholdHU = 500.0;
  double contrastPercentile = 90.0;
  double minimumThresholdHU = 250.0;
  std::optional<PointType> injectionPointMm; // absent: keep the largest component
  // When no component contains the injection point, the nearest within this distance is kept
  // (a cannula tip usually sits in a streak-artefact hole of the mask).
  double injectionSearchRadiusMm = 10.0;
  double closingRadiusMm = 0.0; // 0: no closing
};

struct SegmentationResult {
  MaskType::Pointer mask; // 0/1 on the input grid
  double thresholdHU = 0.0;       // the threshold on (post - pre) that made the mask
  std::string thresholdRule;      // "half-contrast" or "fixed"
  double cementContrastHU = 0.0;  // C of the half-contrast rule; 0 for "fixed" or when none was found
  std::size_t voxels = 0;
  double volumeMl = 0.0;
  std::size_t componentsFound = 0; // above threshold, before selection
  // "injection-point", "nearest-to-injection-point", "largest", or "none" (no cement found)
  std::string selection;
  double distanceToInjectionPointMm = 0.0; // for "nearest-to-injection-point"
};

// post - pre, voxel by voxel. Throws std::runtime_error if the grids differ.
ImageType::Pointer differenceImage(const ImageType* post, const ImageType* pre);

// Segments the cement in post (registered onto pre's grid). Finding none is not an error: the
// result is an empty mask, volume 0, selection "none".
SegmentationResult segmentCement(const ImageType* post, const ImageType* pre,
                                 const SegmentationOptions& options = {});

// The threshold rule in words, for reports: "half the cement's own contrast (...)" or "above N HU".
std::string describeThresholdRule(const SegmentationOptions& options);

// Volume of the non-zero voxels of a mask, in ml (1 ml = 1000 mm^3).
double maskVolumeMl(const MaskType* mask);

} // namespace cementsph::imaging
