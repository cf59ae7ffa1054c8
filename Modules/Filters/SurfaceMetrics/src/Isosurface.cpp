#include "cementsph/surfacemetrics/Isosurface.h"

#include <vtkFlyingEdges3D.h>
#include <vtkImageCast.h>
#include <vtkImageGaussianSmooth.h>
#include <vtkMatrix3x3.h>
#include <vtkPoints.h>

#include <stdexcept>

namespace cementsph::surfacemetrics {

vtkSmartPointer<vtkPolyData> isosurface(vtkImageData* mask, const IsosurfaceOptions& options) {
  if (!mask) throw std::invalid_argument("isosurface: null mask");
  // Index-aligned shallow copy: same origin and spacing, identity direction.
  auto aligned = vtkSmartPointer<vtkImageData>::New();
  aligned->ShallowCopy(mask);
  aligned->SetDirectionMatrix(1, 0, 0, 0, 1, 0, 0, 0, 1);

  vtkSmartPointer<vtkImageData> input = aligned;
  if (options.smoothingSigmaVoxels > 0.0) {
    auto cast = vtkSmartPointer<vtkImageCast>::New();
    cast->SetInputData(aligned);
    cast->SetOutputScalarTypeToFloat();
    auto smooth = vtkSmartPointer<vtkImageGaussianSmooth>::New();
    smooth->SetInputConnection(cast->GetOutputPort());
    smooth->SetDimensionality(3);
    smooth->SetStandardDeviations(options.smoothingSigmaVoxels, options.smoothingSigmaVoxels,
                                  options.smoothingSigmaVoxels);
    smooth->SetRadiusFactors(3.0, 3.0, 3.0);
    smooth->Update();
    input = smooth->GetOutput();
  }

  auto edges = vtkSmartPointer<vtkFlyingEdges3D>::New();
  edges->SetInputData(input);
  edges->SetValue(0, options.level);
  edges->ComputeNormalsOff();
  edges->ComputeGradientsOff();
  edges->ComputeScalarsOff();
  edges->Update();
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  surface->ShallowCopy(edges->GetOutput());

  // Physical point = origin + D (p - origin) for a point p computed with identity direction.
  const double* d = mask->GetDirectionMatrix()->GetData();
  const bool identity = d[0] == 1 && d[4] == 1 && d[8] == 1 && d[1] == 0 && d[2] == 0 &&
                        d[3] == 0 && d[5] == 0 && d[6] == 0 && d[7] == 0;
  if (!identity && surface->GetNumberOfPoints() > 0) {
    const double* o = mask->GetOrigin();
    auto points = vtkSmartPointer<vtkPoints>::New();
    points->SetDataTypeToDouble();
    const vtkIdType n = surface->GetNumberOfPoints();
    points->SetNumberOfPoints(n);
    for (vtkIdType i = 0; i < n; ++i) {
      double p[3], q[3];
      surface->GetPoint(i, p);
      for (int r = 0; r < 3; ++r)
        q[r] = o[r] + d[3 * r] * (p[0] - o[0]) + d[3 * r + 1] * (p[1] - o[1]) +
               d[3 * r + 2] * (p[2] - o[2]);
      points->SetPoint(i, q);
    }
    surface->SetPoints(points);
  }
  return surface;
}

} // namespace cementsph::surfacemetrics
