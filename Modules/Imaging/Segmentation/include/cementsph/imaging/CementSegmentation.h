// Cement segmentation: registered post minus pre, threshold, keep the connected component at the
// injection site (or the largest), optional morphological closing; volume in ml.
// Both volumes must share one grid (resample the post volume onto the pre grid first).
#pragma once

#include "cementsph/imaging/ImageTypes.h"

#include <optional>
#include <string>

namespace cementsph::imaging {

struct SegmentationOptions {
  // Cement raises HU by ~1000-3000 over marrow and trabecular bone; 500 HU keeps clear of CT noise
  // and of the partial-volume differences left at bone edges by a sub-voxel registration error.
  double differenceThresholdHU = 500.0;
  std::optional<PointType> injectionPointMm; // absent: keep the largest component
  // When no component contains the injection point, the nearest within this distance is kept
  // (a cannula tip usually sits in a streak-artefact hole of the mask).
  double injectionSearchRadiusMm = 10.0;
  double closingRadiusMm = 0.0; // 0: no closing
};

struct SegmentationResult {
  MaskType::Pointer mask; // 0/1 on the input grid
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

// Volume of the non-zero voxels of a mask, in ml (1 ml = 1000 mm^3).
double maskVolumeMl(const MaskType* mask);

} // namespace cementsph::imaging
