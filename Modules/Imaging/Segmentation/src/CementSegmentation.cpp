#include "cementsph/imaging/CementSegmentation.h"

#include "cementsph/imaging/VolumeIO.h"

#include <itkBinaryBallStructuringElement.h>
#include <itkBinaryMorphologicalClosingImageFilter.h>
#include <itkConnectedComponentImageFilter.h>
#include <itkImageRegionConstIteratorWithIndex.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
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

namespace {

using LabelImage = itk::Image<std::uint32_t, 3>;

struct SelectedComponent {
  MaskType::Pointer mask; // 0/1: the kept component only
  std::size_t componentsFound = 0;
  std::string selection; // as SegmentationResult::selection
  double distanceToInjectionPointMm = 0.0;
};

// (difference > threshold), its connected components, and the one the options select.
SelectedComponent selectComponent(const ImageType* diff, double thresholdHU, const SegmentationOptions& options) {
  auto candidate = allocateLike<MaskType>(diff);
  const std::size_t n = diff->GetLargestPossibleRegion().GetNumberOfPixels();
  {
    const float* d = diff->GetBufferPointer();
    auto* m = candidate->GetBufferPointer();
    const auto threshold = static_cast<float>(thresholdHU);
    for (std::size_t i = 0; i < n; ++i) m[i] = d[i] > threshold ? 1 : 0;
  }

  auto components = itk::ConnectedComponentImageFilter<MaskType, LabelImage>::New();
  components->SetInput(candidate);
  components->SetFullyConnected(false); // face neighbours: thin bridges through noise do not join
  components->Update();
  const LabelImage* labels = components->GetOutput();

  SelectedComponent result;
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
  result.mask = candidate;
  return result;
}

// The p-th percentile (nearest rank) of the difference over the mask's voxels; 0 for an empty mask.
double percentileInMask(const ImageType* diff, const MaskType* mask, double percentile) {
  std::vector<float> values;
  const std::size_t n = diff->GetLargestPossibleRegion().GetNumberOfPixels();
  const float* d = diff->GetBufferPointer();
  const auto* m = mask->GetBufferPointer();
  for (std::size_t i = 0; i < n; ++i)
    if (m[i] != 0) values.push_back(d[i]);
  if (values.empty()) return 0.0;
  const double rank = std::clamp(percentile, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const auto k = static_cast<std::size_t>(std::lround(rank));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

} // namespace

std::string describeThresholdRule(const SegmentationOptions& options) {
  auto hu = [](double v) {
    std::ostringstream text;
    text << v;
    return text.str();
  };
  if (options.differenceThresholdHU) return "above a fixed " + hu(*options.differenceThresholdHU) + " HU";
  return "above half the cement's own contrast (the " + hu(options.contrastPercentile) +
         "th percentile of the difference in the component above " + hu(options.seedThresholdHU) +
         " HU, halved; at least " + hu(options.minimumThresholdHU) + " HU)";
}

SegmentationResult segmentCement(const ImageType* post, const ImageType* pre,
                                 const SegmentationOptions& options) {
  for (const double v : {options.seedThresholdHU, options.contrastPercentile, options.minimumThresholdHU,
                         options.differenceThresholdHU.value_or(0.0)}) {
    if (!std::isfinite(v)) throw std::invalid_argument("cement segmentation: a threshold option is not finite");
  }
  const ImageType::Pointer diff = differenceImage(post, pre);
  SegmentationResult result;
  SelectedComponent chosen;
  if (options.differenceThresholdHU) {
    result.thresholdRule = "fixed";
    result.thresholdHU = *options.differenceThresholdHU;
    chosen = selectComponent(diff, result.thresholdHU, options);
  } else {
    result.thresholdRule = "half-contrast";
    const SelectedComponent seed = selectComponent(diff, options.seedThresholdHU, options);
    if (seed.selection == "none") {
      result.thresholdHU = options.seedThresholdHU;
      chosen = seed;
    } else {
      result.cementContrastHU = percentileInMask(diff, seed.mask, options.contrastPercentile);
      result.thresholdHU = std::max(0.5 * result.cementContrastHU, options.minimumThresholdHU);
      chosen = selectComponent(diff, result.thresholdHU, options);
    }
  }
  result.componentsFound = chosen.componentsFound;
  result.selection = chosen.selection;
  result.distanceToInjectionPointMm = chosen.distanceToInjectionPointMm;
  const std::size_t n = pre->GetLargestPossibleRegion().GetNumberOfPixels();

  MaskType::Pointer mask = chosen.mask;
  if (chosen.selection != "none" && options.closingRadiusMm > 0.0) {
    using Ball = itk::BinaryBallStructuringElement<std::uint8_t, 3>;
    Ball ball;
    Ball::SizeType radius;
    for (unsigned i = 0; i < 3; ++i)
      radius[i] = static_cast<itk::SizeValueType>(
          std::lround(options.closingRadiusMm / pre->GetSpacing()[i]));
    ball.SetRadius(radius);
    ball.CreateStructuringElement();
    auto closing = itk::BinaryMorphologicalClosingImageFilter<MaskType, MaskType, Ball>::New();
    closing->SetInput(chosen.mask);
    closing->SetKernel(ball);
    closing->SetForegroundValue(1);
    closing->SetSafeBorder(true);
    closing->Update();
    mask = closing->GetOutput();
    mask->DisconnectPipeline();
  }
  result.mask = mask;
  result.voxels = 0;
  const auto* mm = mask->GetBufferPointer();
  for (std::size_t i = 0; i < n; ++i) result.voxels += mm[i] != 0;
  result.volumeMl = static_cast<double>(result.voxels) * voxelVolumeMm3(mask) / 1000.0;
  return result;
}

} // namespace cementsph::imaging
