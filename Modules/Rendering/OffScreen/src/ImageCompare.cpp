#include "cementsph/rendering/ImageCompare.h"

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace cementsph::rendering {
namespace {

struct RgbImage {
  int width = 0, height = 0;
  std::vector<float> rgb; // 3 values per pixel, each in [0, 1]
};

RgbImage readPng(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) {
    throw std::runtime_error("image comparison: " + path.string() + " does not exist");
  }
  vtkNew<vtkPNGReader> reader;
  if (reader->CanReadFile(path.string().c_str()) == 0) {
    throw std::runtime_error("image comparison: " + path.string() + " is not a PNG file");
  }
  reader->SetFileName(path.string().c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  vtkDataArray* scalars = image != nullptr ? image->GetPointData()->GetScalars() : nullptr;
  if (scalars == nullptr || reader->GetErrorCode() != 0) {
    throw std::runtime_error("image comparison: could not read " + path.string());
  }
  int dims[3];
  image->GetDimensions(dims);
  RgbImage out;
  out.width = dims[0];
  out.height = dims[1];
  // 8- and 16-bit PNGs both map to [0, 1].
  const double full = scalars->GetDataTypeSize() == 1 ? 255.0 : 65535.0;
  const int components = scalars->GetNumberOfComponents();
  // Grey (+alpha) counts as R = G = B; alpha is ignored.
  const std::array<int, 3> channel = components >= 3 ? std::array<int, 3>{0, 1, 2} : std::array<int, 3>{0, 0, 0};
  const vtkIdType pixels = scalars->GetNumberOfTuples();
  out.rgb.resize(static_cast<std::size_t>(pixels) * 3);
  for (vtkIdType p = 0; p < pixels; ++p) {
    for (int c = 0; c < 3; ++c) {
      out.rgb[static_cast<std::size_t>(p) * 3 + c] =
          static_cast<float>(scalars->GetComponent(p, channel[static_cast<std::size_t>(c)]) / full);
    }
  }
  return out;
}

} // namespace

namespace {

std::pair<RgbImage, RgbImage> readSameSizePair(const std::filesystem::path& a, const std::filesystem::path& b) {
  RgbImage imageA = readPng(a);
  RgbImage imageB = readPng(b);
  if (imageA.width != imageB.width || imageA.height != imageB.height) {
    throw std::runtime_error("image comparison: sizes differ, " + a.string() + " is " +
                             std::to_string(imageA.width) + " x " + std::to_string(imageA.height) + ", " +
                             b.string() + " is " + std::to_string(imageB.width) + " x " +
                             std::to_string(imageB.height));
  }
  return {std::move(imageA), std::move(imageB)};
}

// True if pixel (x, y) of `from` has no pixel within kVisibleChannelDifference in the 3 x 3 neighbourhood
// of (x, y) in `in`.
bool hasNoMatchNearby(const RgbImage& from, const RgbImage& in, int x, int y) {
  const float* p = &from.rgb[(static_cast<std::size_t>(y) * static_cast<std::size_t>(from.width) +
                              static_cast<std::size_t>(x)) * 3];
  for (int ny = std::max(0, y - 1); ny <= std::min(in.height - 1, y + 1); ++ny) {
    for (int nx = std::max(0, x - 1); nx <= std::min(in.width - 1, x + 1); ++nx) {
      const float* q = &in.rgb[(static_cast<std::size_t>(ny) * static_cast<std::size_t>(in.width) +
                                static_cast<std::size_t>(nx)) * 3];
      if (std::abs(p[0] - q[0]) <= kVisibleChannelDifference && std::abs(p[1] - q[1]) <= kVisibleChannelDifference &&
          std::abs(p[2] - q[2]) <= kVisibleChannelDifference) {
        return false;
      }
    }
  }
  return true;
}

} // namespace

double imageDifference(const std::filesystem::path& a, const std::filesystem::path& b) {
  const auto [imageA, imageB] = readSameSizePair(a, b);
  if (imageA.rgb.empty()) return 0.0;
  std::size_t changed = 0;
  for (int y = 0; y < imageA.height; ++y) {
    for (int x = 0; x < imageA.width; ++x) {
      if (hasNoMatchNearby(imageA, imageB, x, y) || hasNoMatchNearby(imageB, imageA, x, y)) ++changed;
    }
  }
  return static_cast<double>(changed) / (static_cast<double>(imageA.width) * static_cast<double>(imageA.height));
}

double meanAbsoluteDifference(const std::filesystem::path& a, const std::filesystem::path& b) {
  const auto [imageA, imageB] = readSameSizePair(a, b);
  if (imageA.rgb.empty()) return 0.0;
  double sum = 0.0;
  for (std::size_t i = 0; i < imageA.rgb.size(); ++i) {
    sum += std::abs(static_cast<double>(imageA.rgb[i]) - static_cast<double>(imageB.rgb[i]));
  }
  return sum / static_cast<double>(imageA.rgb.size());
}

} // namespace cementsph::rendering
