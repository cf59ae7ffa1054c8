#include "cementsph/surfacemetrics/VolumeMetrics.h"

#include <vtkDataArray.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>

#include <cmath>
#include <stdexcept>

namespace cementsph::surfacemetrics {

namespace {

vtkDataArray* scalarsOf(vtkImageData* mask) {
  if (!mask || !mask->GetPointData()->GetScalars())
    throw std::invalid_argument("volume metrics: mask has no scalars");
  return mask->GetPointData()->GetScalars();
}

// Calls f(i, j, k) for every inside voxel.
template <typename F> void forEachInside(vtkImageData* mask, F&& f) {
  vtkDataArray* s = scalarsOf(mask);
  int dims[3];
  mask->GetDimensions(dims);
  vtkIdType id = 0;
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i, ++id)
        if (s->GetComponent(id, 0) != 0.0) f(i, j, k);
}

} // namespace

Point3 voxelCentre(vtkImageData* image, int i, int j, int k) {
  const double* o = image->GetOrigin();
  const double* s = image->GetSpacing();
  const int* e = image->GetExtent();
  const double* d = image->GetDirectionMatrix()->GetData();
  const double u[3] = {s[0] * (i + e[0]), s[1] * (j + e[2]), s[2] * (k + e[4])};
  Point3 p;
  for (int r = 0; r < 3; ++r) p[r] = o[r] + d[3 * r] * u[0] + d[3 * r + 1] * u[1] + d[3 * r + 2] * u[2];
  return p;
}

Overlap overlap(vtkImageData* a, vtkImageData* b) {
  int da[3], db[3];
  a->GetDimensions(da);
  b->GetDimensions(db);
  for (int i = 0; i < 3; ++i)
    if (da[i] != db[i] || std::abs(a->GetSpacing()[i] - b->GetSpacing()[i]) > 1e-6 ||
        std::abs(a->GetOrigin()[i] - b->GetOrigin()[i]) > 1e-4)
      throw std::invalid_argument("overlap: the two masks are not on one grid");
  vtkDataArray* sa = scalarsOf(a);
  vtkDataArray* sb = scalarsOf(b);
  Overlap o;
  const vtkIdType n = sa->GetNumberOfTuples();
  for (vtkIdType i = 0; i < n; ++i) {
    const bool ina = sa->GetComponent(i, 0) != 0.0;
    const bool inb = sb->GetComponent(i, 0) != 0.0;
    o.voxelsA += ina;
    o.voxelsB += inb;
    o.voxelsBoth += ina && inb;
  }
  const auto both = static_cast<double>(o.voxelsBoth);
  const auto sum = static_cast<double>(o.voxelsA + o.voxelsB);
  o.dice = sum > 0 ? 2.0 * both / sum : 1.0;
  o.jaccard = sum > 0 ? both / (sum - both) : 1.0;
  return o;
}

std::size_t countVoxels(vtkImageData* mask) {
  std::size_t n = 0;
  forEachInside(mask, [&](int, int, int) { ++n; });
  return n;
}

double volumeMl(vtkImageData* mask) {
  const double* s = mask->GetSpacing();
  return static_cast<double>(countVoxels(mask)) * s[0] * s[1] * s[2] / 1000.0;
}

Point3 centroidMm(vtkImageData* mask, bool* ok) {
  Point3 sum{0, 0, 0};
  std::size_t n = 0;
  forEachInside(mask, [&](int i, int j, int k) {
    const Point3 p = voxelCentre(mask, i, j, k);
    for (int r = 0; r < 3; ++r) sum[r] += p[r];
    ++n;
  });
  if (ok) *ok = n > 0;
  if (n == 0) return {0, 0, 0};
  for (auto& v : sum) v /= static_cast<double>(n);
  return sum;
}

double meanSpreadingDistanceMm(vtkImageData* mask, const Point3& c) {
  double sum = 0.0;
  std::size_t n = 0;
  forEachInside(mask, [&](int i, int j, int k) {
    const Point3 p = voxelCentre(mask, i, j, k);
    sum += std::sqrt((p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) +
                     (p[2] - c[2]) * (p[2] - c[2]));
    ++n;
  });
  return n > 0 ? sum / static_cast<double>(n) : 0.0;
}

} // namespace cementsph::surfacemetrics
