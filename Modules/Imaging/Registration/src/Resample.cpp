// Resampling a moving image onto a fixed grid, and transform files.
#include "cementsph/imaging/AffineRegistration.h"

#include "cementsph/imaging/AtomicFile.h"

#include <itkHDF5TransformIOFactory.h>
#include <itkLinearInterpolateImageFunction.h>
#include <itkMatlabTransformIOFactory.h>
#include <itkResampleImageFilter.h>
#include <itkTransformFileReader.h>
#include <itkTransformFileWriter.h>
#include <itkTxtTransformIOFactory.h>

#include <filesystem>
#include <mutex>
#include <stdexcept>

namespace cementsph::imaging {

ImageType::Pointer resampleOnto(const ImageType* moving, const ImageType* fixedGrid,
                                const itk::Transform<double, 3, 3>* transform, float outsideValue) {
  auto resample = itk::ResampleImageFilter<ImageType, ImageType>::New();
  resample->SetInput(moving);
  resample->SetTransform(transform);
  resample->SetInterpolator(itk::LinearInterpolateImageFunction<ImageType, double>::New());
  resample->UseReferenceImageOn();
  resample->SetReferenceImage(fixedGrid);
  resample->SetDefaultPixelValue(outsideValue);
  resample->Update();
  ImageType::Pointer out = resample->GetOutput();
  out->DisconnectPipeline();
  return out;
}

namespace {
// Transform IO goes through ITK's factories; register them once, explicitly, so nothing depends
// on UseITK's generated registration headers.
void registerTransformIO() {
  static std::once_flag once;
  std::call_once(once, [] {
    itk::TxtTransformIOFactory::RegisterOneFactory();
    itk::MatlabTransformIOFactory::RegisterOneFactory();
    itk::HDF5TransformIOFactory::RegisterOneFactory();
  });
}
} // namespace

void writeTransform(const AffineTransformType* transform, const std::string& path) {
  registerTransformIO();
  writeAtomically(path, [&](const std::string& tmp) {
    auto writer = itk::TransformFileWriterTemplate<double>::New();
    writer->SetInput(transform);
    writer->SetFileName(tmp);
    try {
      writer->Update();
    } catch (const itk::ExceptionObject& e) {
      throw std::runtime_error(std::string("cannot write transform: ") + e.GetDescription());
    }
  });
}

AffineTransformType::Pointer readTransform(const std::string& path) {
  registerTransformIO();
  if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": no such file");
  auto reader = itk::TransformFileReaderTemplate<double>::New();
  reader->SetFileName(path);
  try {
    reader->Update();
  } catch (const itk::ExceptionObject& e) {
    throw std::runtime_error(path + ": cannot read transform: " + e.GetDescription());
  }
  const auto* list = reader->GetTransformList();
  if (list->empty()) throw std::runtime_error(path + ": no transform in file");
  auto* affine = dynamic_cast<AffineTransformType*>(list->front().GetPointer());
  if (!affine) throw std::runtime_error(path + ": not an affine transform");
  return affine;
}

} // namespace cementsph::imaging
