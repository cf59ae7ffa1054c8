#include "cementsph/imaging/CementSegmentation.h"

#include "cementsph/imaging/VolumeIO.h"

#include <itkBinaryBallStructuringElement.h>
#include <itkBinaryMorphologicalClosingImageFilter.h>
#include <itkConnectedComponentImageFilter.h>
#include <itkImageRegionConstIteratorWithIndex.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace cementsph::imaging {

namespace {
// A new image on reference's grid (contents undefined).
template <typename TImage> typename TImage::Pointer allocateLike(const itk::ImageBase<3>* reference) {
  auto image = TImage::New();
  image->CopyInformation(reference);
  image->SetRegions(reference->GetLargestPossibleRegion());
  image->Allocate();
  return image;
}

double voxelVolumeMm3(const itk::ImageBase<3>* image) {
  const auto s = image->GetSpacing();
  return s[0] * s[1] * s[2];
}
} // namespace

double maskVolumeMl(const MaskType* mask) {
  std::size_t n = 0;
  const auto* p = mask->GetBufferPointer();
  const std::size_t total = mask->GetLargestPossibleRegion().GetNumberOfPixels();
  for (std::size_t i = 0; i < total; ++i) n += p[i] != 0;
  return static_cast<double>(n) * voxelVolumeMm3(mask) / 1000.0;
}

ImageType::Pointer differenceImage(const ImageType* post, const ImageType* pre) {
  if (!geometryOf(post).sameGrid(geometryOf(pre)))
    throw std::runtime_error("cement segmentation: post and pre volumes are not on one grid "
                             "(register and resample the post volume first)");
  auto out = allocateLike<ImageType>(pre);
  const std::size_t n = pre->GetLargestPossibleRegion().GetNumberOfPixels();
  const float* a = post->GetBufferPointer();
  const float* b = pre->GetBufferPointer();
  float* d = out->GetBufferPointer();
  for (std::size_t i = 0; i < n; ++i) d[i] = a[i] - b[i];
  return out;
}

SegmentationResult segmentCement(const ImageType* post, const ImageType* pre,
                                 const SegmentationOptions& options) {
  const ImageType::Pointer diff = differenceImage(post, pre);
  auto candidate = allocateLike<MaskType>(pre);
  const std::size_t n = pre->GetLargestPossibleRegion().GetNumberOfPixels();
  {
    const float* d = diff->GetBufferPointer();
    auto* m = candidate->GetBufferPointer();
    const auto threshold = static_cast<float>(options.differenceThresholdHU);
    for (std::size_t i = 0; i < n; ++i) m[i] = d[i] > threshold ? 1 : 0;
  }

  using LabelImage = itk::Image<std::uint32_t, 3>;
  auto components = itk::ConnectedComponentImageFilter<MaskType, LabelImage>::New();
  components->SetInput(candidate);
  components->SetFullyConnected(false); // face neighbours: thin bridges through noise do not join
  components->Update();
  const LabelImage* labels = components->GetOutput();

  SegmentationResult result;
  result.componentsFound = components->GetObjectCount();
  std::vector<std::size_t> sizes(result.componentsFound + 1, 0);
  const auto* l = labels->GetBufferPointer();
  for (std::size_t i = 0; i < n; ++i) ++sizes[l[i]];

  std::uint32_t keep = 0;
  if (result.componentsFound > 0) {
    if (options.injectionPointMm) {
      const PointType& p = *options.injectionPointMm;
      LabelImage::IndexType index;
      if (labels->TransformPhysicalPointToIndex(p, index) && labels->GetPixel(index) != 0) {
        keep = labels->GetPixel(index);
        result.selection = "injection-point";
      } else {
        double best = std::numeric_limits<double>::infinity();
        itk::ImageRegionConstIteratorWithIndex<LabelImage> it(labels, labels->GetLargestPossibleRegion());
        for (; !it.IsAtEnd(); ++it) {
          if (it.Get() == 0) continue;
          PointType q;
          labels->TransformIndexToPhysicalPoint(it.GetIndex(), q);
          const double dist = q.EuclideanDistanceTo(p);
          if (dist < best) {
            best = dist;
            keep = it.Get();
          }
        }
        if (best <= options.injectionSearchRadiusMm) {
          result.selection = "nearest-to-injection-point";
          result.distanceToInjectionPointMm = best;
        } else {
          keep = 0; // the bright regions are elsewhere: not the cement injected here
        }
      }
    } else {
      for (std::uint32_t label = 1; label < sizes.size(); ++label)
        if (sizes[label] > sizes[keep] || keep == 0) keep = label;
      result.selection = "largest";
    }
  }
  if (keep == 0) result.selection = "none";

  auto* m = candidate->GetBufferPointer();
  for (std::size_t i = 0; i < n; ++i) m[i] = (keep != 0 && l[i] == keep) ? 1 : 0;

  MaskType::Pointer mask = candidate;
  if (keep != 0 && options.closingRadiusMm > 0.0) {
    using Ball = itk::BinaryBallStructuringElement<std::uint8_t, 3>;
    Ball ball;
    Ball::SizeType radius;
    for (unsigned i = 0; i < 3; ++i)
      radius[i] = static_cast<itk::SizeValueType>(
          std::lround(options.closingRadiusMm / pre->GetSpacing()[i]));
    ball.SetRadius(radius);
    ball.CreateStructuringElement();
    auto closing = itk::BinaryMorphologicalClosingImageFilter<MaskType, MaskType, Ball>::New();
    closing->SetInput(candidate);
    closing->SetKernel(ball);
    closing->SetForegroundValue(1);
    closing->SetSafeBorder(true);
    closing->Update();
    mask = closing->GetOutput();
    mask->DisconnectPipeline();
  }
  result.mask = mask;
  const auto* mm = mask->GetBufferPointer();
  for (std::size_t i = 0; i < n; ++i) result.voxels += mm[i] != 0;
  result.volumeMl = static_cast<double>(result.voxels) * voxelVolumeMm3(mask) / 1000.0;
  return result;
}

} // namespace cementsph::imaging
