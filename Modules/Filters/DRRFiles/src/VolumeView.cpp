#include "cementsph/drr/VolumeView.h"

#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>

#include <stdexcept>

namespace cementsph::drr {

vtkSmartPointer<vtkImageData> viewAsVtk(const imaging::ImageType* volume) {
  if (volume == nullptr) throw std::runtime_error("viewAsVtk: no volume");
  const auto region = volume->GetBufferedRegion();
  const auto size = region.GetSize();
  auto view = vtkSmartPointer<vtkImageData>::New();
  view->SetDimensions(static_cast<int>(size[0]), static_cast<int>(size[1]), static_cast<int>(size[2]));
  // The buffered region may not start at index 0: its first voxel's position is the VTK origin.
  imaging::PointType start;
  volume->TransformIndexToPhysicalPoint(region.GetIndex(), start);
  double direction[9];
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j) direction[3 * i + j] = volume->GetDirection()[i][j];
  view->SetOrigin(start[0], start[1], start[2]);
  view->SetSpacing(volume->GetSpacing()[0], volume->GetSpacing()[1], volume->GetSpacing()[2]);
  view->SetDirectionMatrix(direction);
  auto voxels = vtkSmartPointer<vtkFloatArray>::New();
  // save = 1: VTK never frees (or writes) ITK's buffer; the const_cast is safe because the DRR only reads.
  voxels->SetArray(const_cast<float*>(volume->GetBufferPointer()),
                   static_cast<vtkIdType>(region.GetNumberOfPixels()), 1);
  view->GetPointData()->SetScalars(voxels);
  return view;
}

} // namespace cementsph::drr
