// One DRR of a volume as a plain call: vtkDRRFilter run once, its VTK errors turned into an exception.
// Shared by `cementsph drr` and XraySequence so both refuse the same inputs with the same words.
#pragma once

#include "cementsph/drr/DRRGeometry.h"

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

namespace cementsph::drr {

// The DRR of volumeHU (vtkDRRFilter's output, owned by the caller). threads 0: OpenMP's default.
// Throws std::runtime_error("the DRR could not be computed: <vtkDRRFilter's message>") when the filter
// reports an error or produces no pixels.
vtkSmartPointer<vtkImageData> projectVolume(vtkImageData* volumeHU, const DRRGeometry& geometry, int threads = 0);

} // namespace cementsph::drr
