#include "cementsph/drr/AttenuationVolume.h"

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkMatrix4x4.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>
#include <vtkType.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cementsph::drr {

namespace {

// One pass over the HU: the box of attenuating voxels (HU > -800) per slice and, for inputs that are
// not single-component float, a float copy of the HU (copy == nullptr: none needed).
template <typename T>
void scanSlices(const T* hu, float* copy, const int dims[3], int threads, int* sliceLo, int* sliceHi,
                std::size_t* sliceCount) {
  const std::ptrdiff_t sliceSize = static_cast<std::ptrdiff_t>(dims[0]) * dims[1];
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int k = 0; k < dims[2]; ++k) {
    int lo[2] = {dims[0], dims[1]}, hi[2] = {-1, -1};
    std::size_t count = 0;
    for (int j = 0; j < dims[1]; ++j) {
      const std::ptrdiff_t row = k * sliceSize + static_cast<std::ptrdiff_t>(j) * dims[0];
      for (int i = 0; i < dims[0]; ++i) {
        const float h = static_cast<float>(hu[row + i]);
        if (copy) copy[row + i] = h;
        if (h > AttenuationVolume::kAirThresholdHU) {
          ++count;
          lo[0] = std::min(lo[0], i);
          hi[0] = std::max(hi[0], i);
          lo[1] = std::min(lo[1], j);
          hi[1] = std::max(hi[1], j);
        }
      }
    }
    sliceLo[2 * k] = lo[0];
    sliceLo[2 * k + 1] = lo[1];
    sliceHi[2 * k] = hi[0];
    sliceHi[2 * k + 1] = hi[1];
    sliceCount[k] = count;
  }
}

} // namespace

AttenuationVolume::AttenuationVolume(vtkImageData* image, int threads) {
  if (!image) throw std::invalid_argument("no input image");
  vtkDataArray* scalars = image->GetPointData() ? image->GetPointData()->GetScalars() : nullptr;
  if (!scalars) throw std::invalid_argument("the input image has no scalars");
  int extent[6];
  image->GetExtent(extent);
  for (int a = 0; a < 3; ++a) dims_[a] = extent[2 * a + 1] - extent[2 * a] + 1;
  if (dims_[0] < 1 || dims_[1] < 1 || dims_[2] < 1) throw std::invalid_argument("the input image is empty");
  stride_[0] = 1;
  stride_[1] = dims_[0];
  stride_[2] = static_cast<std::ptrdiff_t>(dims_[0]) * dims_[1];

  // Physical -> structured index (VTK 9.1: origin + direction * (spacing .* ijk)); the extent's
  // start is subtracted so that 0 is the first stored voxel.
  double toPhysical[16], toIndex[16];
  vtkImageData::ComputeIndexToPhysicalMatrix(image->GetOrigin(), image->GetSpacing(),
                                             image->GetDirectionMatrix()->GetData(), toPhysical);
  const double det = vtkMatrix4x4::Determinant(toPhysical);
  if (!(std::abs(det) > 0.0) || !std::isfinite(det))
    throw std::invalid_argument("the input image's spacing or direction matrix is singular");
  vtkMatrix4x4::Invert(toPhysical, toIndex);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) physicalToIndex_[4 * r + c] = toIndex[4 * r + c];
    physicalToIndex_[4 * r + 3] -= extent[2 * r];
  }
  for (double v : physicalToIndex_)
    if (!std::isfinite(v))
      throw std::invalid_argument("the input image's spacing or direction matrix is singular");

  const std::size_t n = static_cast<std::size_t>(stride_[2]) * dims_[2];
  if (static_cast<std::size_t>(scalars->GetNumberOfTuples()) < n)
    throw std::invalid_argument("the input image has fewer scalars than voxels");
  std::vector<int> sliceLo(2 * dims_[2]), sliceHi(2 * dims_[2]);
  std::vector<std::size_t> sliceCount(dims_[2]);
  const int nThreads = std::max(1, threads);
  if (scalars->GetNumberOfComponents() == 1 && scalars->GetDataType() == VTK_FLOAT) {
    // The usual case: the walk reads the input's own HU (no 4-bytes-a-voxel copy to allocate, fill
    // and page in, which cost as much as a fifth of a DRR).
    hu_ = static_cast<const float*>(scalars->GetVoidPointer(0));
    scanSlices(hu_, nullptr, dims_, nThreads, sliceLo.data(), sliceHi.data(), sliceCount.data());
  } else if (scalars->GetNumberOfComponents() == 1) {
    ownedHU_.resize(n);
    switch (scalars->GetDataType()) {
      vtkTemplateMacro(scanSlices(static_cast<const VTK_TT*>(scalars->GetVoidPointer(0)), ownedHU_.data(),
                                  dims_, nThreads, sliceLo.data(), sliceHi.data(), sliceCount.data()));
    default:
      throw std::invalid_argument("the input image's scalar type is not numeric");
    }
    hu_ = ownedHU_.data();
  } else {
    // Rare (multi-component CT); the first component is HU.
    std::vector<double> first(n);
    for (std::size_t v = 0; v < n; ++v) first[v] = scalars->GetComponent(static_cast<vtkIdType>(v), 0);
    ownedHU_.resize(n);
    scanSlices(first.data(), ownedHU_.data(), dims_, nThreads, sliceLo.data(), sliceHi.data(), sliceCount.data());
    hu_ = ownedHU_.data();
  }

  lo_[0] = dims_[0];
  lo_[1] = dims_[1];
  lo_[2] = dims_[2];
  for (int k = 0; k < dims_[2]; ++k) {
    if (sliceCount[k] == 0) continue;
    attenuating_ += sliceCount[k];
    for (int a = 0; a < 2; ++a) {
      lo_[a] = std::min(lo_[a], sliceLo[2 * k + a]);
      hi_[a] = std::max(hi_[a], sliceHi[2 * k + a]);
    }
    lo_[2] = std::min(lo_[2], k);
    hi_[2] = std::max(hi_[2], k);
  }
}

double AttenuationVolume::lineIntegral(const Ray& ray) const {
  if (attenuating_ == 0) return 0.0;
  // The ray in continuous index space: q(t) = q0 + t * b, t still in mm along the physical ray.
  double q0[3], b[3];
  const double* m = physicalToIndex_;
  for (int r = 0; r < 3; ++r) {
    q0[r] = m[4 * r] * ray.origin[0] + m[4 * r + 1] * ray.origin[1] + m[4 * r + 2] * ray.origin[2] + m[4 * r + 3];
    b[r] = m[4 * r] * ray.direction[0] + m[4 * r + 1] * ray.direction[1] + m[4 * r + 2] * ray.direction[2];
  }

  // Clip to the box of attenuating voxels; voxel k spans [k - 0.5, k + 0.5] in index space.
  double t0 = ray.tMin, t1 = ray.tMax;
  for (int a = 0; a < 3; ++a) {
    const double boxLo = lo_[a] - 0.5, boxHi = hi_[a] + 0.5;
    if (b[a] == 0.0) {
      if (q0[a] < boxLo || q0[a] >= boxHi) return 0.0;
      continue;
    }
    double ta = (boxLo - q0[a]) / b[a], tb = (boxHi - q0[a]) / b[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (!(t0 < t1)) return 0.0;

  // Amanatides-Woo set-up: the voxel at the entry point, the t of the next boundary on each axis,
  // the t between boundaries and how many boundaries remain inside the box. The entry voxel is
  // clamped into the box because rounding can put an entry point on the box's face a hair outside.
  double tNext[3], tDelta[3];
  int remaining[3];
  std::ptrdiff_t offset = 0, stepOffset[3];
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double q = q0[a] + t0 * b[a];
    const int idx = std::clamp(static_cast<int>(std::floor(q + 0.5)), lo_[a], hi_[a]);
    offset += idx * stride_[a];
    if (b[a] > 0.0) {
      tNext[a] = t0 + (idx + 0.5 - q) / b[a];
      tDelta[a] = 1.0 / b[a];
      stepOffset[a] = stride_[a];
      remaining[a] = hi_[a] - idx;
    } else if (b[a] < 0.0) {
      tNext[a] = t0 + (idx - 0.5 - q) / b[a];
      tDelta[a] = -1.0 / b[a];
      stepOffset[a] = -stride_[a];
      remaining[a] = idx - lo_[a];
    } else {
      tNext[a] = kInf;
      tDelta[a] = kInf;
      stepOffset[a] = 0;
      remaining[a] = 0;
    }
  }

  // The walk, arranged for speed (it is ~all of a DRR's time):
  //  - the axis with the most crossings ("main", the one the ray runs most along) gets a tight
  //    inner loop that only asks "does main cross before the next crossing of either other axis?";
  //    the other two are stepped in between, rarely for the near-axial rays of a DRR;
  //  - scalars rather than arrays indexed by the axis, so the hot loop stays in registers;
  //  - the next boundary is base + k * delta from an integer count k, not t += delta: no 4-cycle add
  //    chain from step to step, and no drift.
  int order[3] = {0, 1, 2};
  const auto absb = [&](int a) { return std::abs(b[a]); };
  if (absb(order[1]) > absb(order[0])) std::swap(order[0], order[1]);
  if (absb(order[2]) > absb(order[0])) std::swap(order[0], order[2]);
  const int am = order[0], ao = order[1], ap = order[2];
  const float* hu = hu_ + offset;
  // mu from HU at each voxel (see muFromHU): a compare and a multiply-add, off the critical path.
  const auto mu = [](const float* h) {
    return *h > static_cast<float>(kAirThresholdHU) ? kMuWaterPerMm + (kMuWaterPerMm / 1000.0) * *h : 0.0;
  };
  const double bm = tNext[am], bo = tNext[ao], bp = tNext[ap];
  const double dm = tDelta[am], dO = tDelta[ao], dp = tDelta[ap];
  const std::ptrdiff_t sm = stepOffset[am], so = stepOffset[ao], sp = stepOffset[ap];
  int nm = remaining[am], no = remaining[ao], np = remaining[ap];
  double tm = bm, to = bo, tp = bp;
  int km = 0, ko = 0, kp = 0;
  double sum = 0.0, t = t0;
  for (;;) {
    const double tOther = std::min(to, tp);
    const double tStop = std::min(tOther, t1);
    while (tm < tStop) {
      sum += mu(hu) * (tm - t);
      t = tm;
      if (nm-- == 0) return sum; // left the box (only through rounding before t1)
      tm = bm + (++km) * dm;
      hu += sm;
    }
    if (tOther >= t1) break;
    sum += mu(hu) * (tOther - t);
    t = tOther;
    if (to <= tp) {
      if (no-- == 0) return sum;
      to = bo + (++ko) * dO;
      hu += so;
    } else {
      if (np-- == 0) return sum;
      tp = bp + (++kp) * dp;
      hu += sp;
    }
  }
  return sum + mu(hu) * (t1 - t);
}

} // namespace cementsph::drr
