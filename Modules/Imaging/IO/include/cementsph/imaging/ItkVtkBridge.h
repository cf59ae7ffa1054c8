// The ITK <-> VTK image bridge. Debian's ITK 5.2 has no ITKVtkGlue (no itk::ImageToVTKImageFilter),
// so this copies voxels and carries the full geometry: origin, spacing and the direction matrix
// (vtkImageData has one since VTK 9.1). Copies, not shared buffers: the two sides own their memory
// and the volumes here are small (a few million voxels).
#pragma once

#include "cementsph/imaging/ImageTypes.h"

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

namespace cementsph::imaging {

vtkSmartPointer<vtkImageData> toVtk(const ImageType* image); // float scalars
vtkSmartPointer<vtkImageData> toVtk(const MaskType* mask);   // unsigned char scalars

// Any scalar type is accepted (first component); the result is float.
ImageType::Pointer imageFromVtk(vtkImageData* image);
MaskType::Pointer maskFromVtk(vtkImageData* image); // non-zero -> 1

} // namespace cementsph::imaging
