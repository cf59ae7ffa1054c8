// The image types of the imaging modules. Intensities are float (CT in HU); masks are 0/1 bytes.
// Physical coordinates are millimetres, as in ITK and DICOM.
#pragma once

#include <itkImage.h>

#include <cstdint>

namespace cementsph::imaging {

constexpr unsigned int kDimension = 3;
using ImageType = itk::Image<float, kDimension>;
using MaskType = itk::Image<std::uint8_t, kDimension>;
using PointType = ImageType::PointType;

} // namespace cementsph::imaging
