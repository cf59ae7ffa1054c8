// One segmented cement, as the paper measures it on CT (Basafa et al. 2013, "Comparison with experiments"):
// the cement mask (post minus pre above a threshold, the component at the injection point), its isosurface,
// volume, centroid and mean spreading distance from the injection point. Shared by `cementsph compare` and
// `cementsph study`, so the two measure a simulated CT in exactly the same way.
#pragma once

#include "cementsph/imaging/CementSegmentation.h"
#include "cementsph/surfacemetrics/VolumeMetrics.h"

#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

namespace cementsph::study {

struct AnalysedCement {
  imaging::SegmentationResult segmentation;
  vtkSmartPointer<vtkImageData> vtkMask;  // the mask as VTK image (origin, spacing, direction kept)
  vtkSmartPointer<vtkPolyData> surface;   // isosurface in mm; null when no cement was found
  double spreadingMm = 0.0;               // mean distance of cement voxel centres from the injection point
  surfacemetrics::Point3 centroid{0, 0, 0};
  bool found() const { return segmentation.voxels > 0; }
};

// Segments the cement in `volume` (on `pre`'s grid: resample first) against `pre`, and measures it.
// smoothingVoxels: Gaussian sigma before isosurfacing (IsosurfaceOptions). Finding no cement is not an
// error (found() is false, no surface).
AnalysedCement analyseCement(const imaging::ImageType* volume, const imaging::ImageType* pre,
                             const imaging::SegmentationOptions& options, const surfacemetrics::Point3& injectionMm,
                             double smoothingVoxels);

} // namespace cementsph::study
