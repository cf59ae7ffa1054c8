#include "DRRTestSupport.h"

#include "cementsph/drr/vtkDRRFilter.h"

#include <gtest/gtest.h>
#include <vtkNew.h>

#include <vtkFloatArray.h>
#include <vtkPointData.h>

#include <cmath>
#include <vector>

namespace cementsph::drrtest {

VolumeGrid centredGrid(const std::array<int, 3>& dims, const Vec3& spacing, const Vec3& centreMm) {
  VolumeGrid g;
  g.dims = dims;
  g.spacing = spacing;
  for (int a = 0; a < 3; ++a) g.origin[a] = centreMm[a] - 0.5 * (dims[a] - 1) * spacing[a];
  return g;
}

vtkSmartPointer<vtkImageData> voxelise(const VolumeGrid& grid, const Phantom& phantom) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(grid.dims.data());
  image->SetSpacing(grid.spacing.data());
  image->SetOrigin(grid.origin.data());
  image->SetDirectionMatrix(grid.direction.data());
  image->AllocateScalars(VTK_FLOAT, 1);
  float* v = static_cast<float*>(image->GetScalarPointer());
  const int n = grid.subsamples;
  const auto& d = grid.direction;
#pragma omp parallel for schedule(static)
  for (int k = 0; k < grid.dims[2]; ++k)
    for (int j = 0; j < grid.dims[1]; ++j)
      for (int i = 0; i < grid.dims[0]; ++i) {
        double sum = 0.0;
        for (int c = 0; c < n; ++c)
          for (int b = 0; b < n; ++b)
            for (int a = 0; a < n; ++a) {
              const double idx[3] = {i + (a + 0.5) / n - 0.5, j + (b + 0.5) / n - 0.5, k + (c + 0.5) / n - 0.5};
              Vec3 p;
              for (int r = 0; r < 3; ++r)
                p[r] = grid.origin[r] + d[3 * r] * idx[0] * grid.spacing[0] +
                       d[3 * r + 1] * idx[1] * grid.spacing[1] + d[3 * r + 2] * idx[2] * grid.spacing[2];
              sum += phantom(p);
            }
        v[(static_cast<std::size_t>(k) * grid.dims[1] + j) * grid.dims[0] + i] =
            static_cast<float>(sum / (n * n * n));
      }
  return image;
}

Phantom balls(std::vector<Ball> list) {
  return [list = std::move(list)](const Vec3& p) {
    double hu = -1000.0;
    for (const Ball& b : list) {
      const double dx = p[0] - b.centre[0], dy = p[1] - b.centre[1], dz = p[2] - b.centre[2];
      if (dx * dx + dy * dy + dz * dz <= b.radius * b.radius) hu = b.hu;
    }
    return hu;
  };
}

double Drr::sum() const {
  double s = 0;
  for (float x : v) s += x;
  return s;
}

std::array<double, 3> Drr::moments() const {
  double s = 0, si = 0, sj = 0;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i) {
      s += at(i, j);
      si += at(i, j) * i;
      sj += at(i, j) * j;
    }
  const double ci = si / s, cj = sj / s;
  double r2 = 0;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i) r2 += at(i, j) * ((i - ci) * (i - ci) + (j - cj) * (j - cj));
  return {ci, cj, std::sqrt(r2 / s)};
}

Drr project(vtkImageData* volume, const drr::DRRGeometry& g, int threads) {
  vtkNew<vtkDRRFilter> f;
  f->SetInputData(volume);
  f->SetGeometry(g);
  f->SetNumberOfThreads(threads);
  f->Update();
  EXPECT_EQ(f->GetErrorCode(), 0u);
  vtkImageData* out = f->GetOutput();
  Drr d;
  int dims[3];
  out->GetDimensions(dims);
  d.cols = dims[0];
  d.rows = dims[1];
  EXPECT_EQ(dims[2], 1);
  EXPECT_EQ(out->GetScalarType(), VTK_FLOAT);
  d.pixelW = out->GetSpacing()[0];
  d.pixelH = out->GetSpacing()[1];
  const float* p = static_cast<const float*>(out->GetScalarPointer());
  d.v.assign(p, p + static_cast<std::size_t>(d.cols) * d.rows);
  return d;
}

drr::DRRGeometry detector(int n, double sizeMm, bool parallel, const Vec3& iso) {
  drr::DRRGeometry g;
  g.rows = g.cols = n;
  g.heightMm = g.widthMm = sizeMm;
  g.parallel = parallel;
  g.isocenterMm = iso;
  return g;
}

} // namespace cementsph::drrtest
