#include "cementsph/study/AnalysedCement.h"

#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/surfacemetrics/Isosurface.h"

namespace cementsph::study {

AnalysedCement analyseCement(const imaging::ImageType* volume, const imaging::ImageType* pre,
                             const imaging::SegmentationOptions& options, const surfacemetrics::Point3& injectionMm,
                             double smoothingVoxels) {
  AnalysedCement c;
  c.segmentation = imaging::segmentCement(volume, pre, options);
  c.vtkMask = imaging::toVtk(c.segmentation.mask.GetPointer());
  if (c.found()) {
    c.spreadingMm = surfacemetrics::meanSpreadingDistanceMm(c.vtkMask, injectionMm);
    c.centroid = surfacemetrics::centroidMm(c.vtkMask);
    surfacemetrics::IsosurfaceOptions iso;
    iso.smoothingSigmaVoxels = smoothingVoxels;
    c.surface = surfacemetrics::isosurface(c.vtkMask, iso);
  }
  return c;
}

} // namespace cementsph::study
