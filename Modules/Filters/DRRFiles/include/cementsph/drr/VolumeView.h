// A CT volume (ImagingIO's ITK image) as the vtkImageData the DRR filter reads, without a copy. Its own header
// because it names ITK's image type: include it only where CementSPH::ImagingIO is linked too (the DRR module
// links it privately, so DRR's other headers stay free of ITK).
#pragma once

#include "cementsph/imaging/ImageTypes.h"

#include <vtkSmartPointer.h>

class vtkImageData;

namespace cementsph::drr {

// The CT's voxels seen as a vtkImageData without copying them (geometry as imaging::toVtk gives it):
// the DRR only reads them, and a 256x256x200 copy was a tenth of a whole `cementsph drr` run (the copy and
// its page faults). `volume` must outlive the view. Throws std::runtime_error for a null volume.
vtkSmartPointer<vtkImageData> viewAsVtk(const imaging::ImageType* volume);

} // namespace cementsph::drr
