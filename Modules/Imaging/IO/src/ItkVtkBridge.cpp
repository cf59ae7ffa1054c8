#include "cementsph/imaging/ItkVtkBridge.h"

#include <vtkDataArray.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>

#include <algorithm>
#include <stdexcept>

namespace cementsph::imaging {

namespace {

// ITK and VTK both store x fastest, then y, then z, so the voxel order is the same.
template <typename TImage>
vtkSmartPointer<vtkImageData> copyToVtk(const TImage* image, int vtkType) {
  if (!image) throw std::runtime_error("toVtk: null image");
  const auto region = image->GetBufferedRegion();
  const auto size = region.GetSize();
  auto out = vtkSmartPointer<vtkImageData>::New();
  out->SetDimensions(static_cast<int>(size[0]), static_cast<int>(size[1]),
                     static_cast<int>(size[2]));
  double origin[3], spacing[3], direction[9];
  // The buffered region may not start at index 0: fold its start into the VTK origin.
  typename TImage::PointType start;
  image->TransformIndexToPhysicalPoint(region.GetIndex(), start);
  for (unsigned i = 0; i < 3; ++i) {
    origin[i] = start[i];
    spacing[i] = image->GetSpacing()[i];
    for (unsigned j = 0; j < 3; ++j) direction[3 * i + j] = image->GetDirection()[i][j];
  }
  out->SetOrigin(origin);
  out->SetSpacing(spacing);
  out->SetDirectionMatrix(direction);
  out->AllocateScalars(vtkType, 1);
  std::copy_n(image->GetBufferPointer(), region.GetNumberOfPixels(),
              static_cast<typename TImage::PixelType*>(out->GetScalarPointer()));
  return out;
}

template <typename TImage, typename Convert>
typename TImage::Pointer copyFromVtk(vtkImageData* in, Convert convert) {
  if (!in || !in->GetPointData()->GetScalars())
    throw std::runtime_error("fromVtk: image has no scalars");
  int dims[3];
  in->GetDimensions(dims);
  auto out = TImage::New();
  typename TImage::RegionType region;
  typename TImage::SpacingType spacing;
  typename TImage::PointType origin;
  typename TImage::DirectionType direction;
  const double* d = in->GetDirectionMatrix()->GetData();
  for (unsigned i = 0; i < 3; ++i) {
    region.SetSize(i, static_cast<itk::SizeValueType>(dims[i]));
    spacing[i] = in->GetSpacing()[i];
    for (unsigned j = 0; j < 3; ++j) direction[i][j] = d[3 * i + j];
  }
  // VTK's extent may start away from 0: voxel (0,0,0) of the copy is the extent's first voxel.
  const int* extent = in->GetExtent();
  double first[3];
  in->TransformIndexToPhysicalPoint(extent[0], extent[2], extent[4], first);
  for (unsigned i = 0; i < 3; ++i) origin[i] = first[i];
  out->SetRegions(region);
  out->SetSpacing(spacing);
  out->SetOrigin(origin);
  out->SetDirection(direction);
  out->Allocate();
  vtkDataArray* scalars = in->GetPointData()->GetScalars();
  auto* buffer = out->GetBufferPointer();
  const vtkIdType n = scalars->GetNumberOfTuples();
  for (vtkIdType i = 0; i < n; ++i) buffer[i] = convert(scalars->GetComponent(i, 0));
  return out;
}

} // namespace

vtkSmartPointer<vtkImageData> toVtk(const ImageType* image) {
  return copyToVtk(image, VTK_FLOAT);
}

vtkSmartPointer<vtkImageData> toVtk(const MaskType* mask) {
  return copyToVtk(mask, VTK_UNSIGNED_CHAR);
}

ImageType::Pointer imageFromVtk(vtkImageData* image) {
  return copyFromVtk<ImageType>(image, [](double v) { return static_cast<float>(v); });
}

MaskType::Pointer maskFromVtk(vtkImageData* image) {
  return copyFromVtk<MaskType>(image, [](double v) { return std::uint8_t(v != 0.0 ? 1 : 0); });
}

} // namespace cementsph::imaging
