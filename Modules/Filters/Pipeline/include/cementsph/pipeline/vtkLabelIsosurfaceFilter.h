// vtkLabelIsosurfaceFilter: the surface of a label map's region (labels >= InsideFrom count as inside: 1 and 2
// of vtkSPHInjectionFilter's cement labels by default) in physical space, mm, the CT's frame. VTK 9.1's
// vtkFlyingEdges3D and vtkMarchingCubes ignore vtkImageData's direction matrix, so their surface of a CT with
// flipped or swapped axes (a NIfTI from RAS, a sagittal series) lies in the wrong place; this one extracts on
// the index grid and maps the points through the direction afterwards (cementsph/surfacemetrics/Isosurface.h,
// the surfaces `cementsph compare` measures), optionally after Gaussian smoothing of the 0/1 mask.
// Input: vtkImageData (any scalar type; first component). Output: vtkPolyData (triangles; empty for an empty
// region).
#pragma once

#include <vtkPolyDataAlgorithm.h>

class vtkLabelIsosurfaceFilter : public vtkPolyDataAlgorithm {
public:
  static vtkLabelIsosurfaceFilter* New();
  vtkTypeMacro(vtkLabelIsosurfaceFilter, vtkPolyDataAlgorithm)
  void PrintSelf(ostream& os, vtkIndent indent) override;

  // Voxels whose value is at least this are inside (default 1).
  vtkSetMacro(InsideFrom, double);
  vtkGetMacro(InsideFrom, double);
  // Gaussian smoothing of the 0/1 mask before the 0.5-isosurface, in voxels (0: the staircase surface;
  // `cementsph compare` uses 1: a staircase biases surface distances low by 0.15-0.2 voxel).
  vtkSetMacro(SmoothingSigmaVoxels, double);
  vtkGetMacro(SmoothingSigmaVoxels, double);

protected:
  vtkLabelIsosurfaceFilter() = default;
  ~vtkLabelIsosurfaceFilter() override = default;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                  vtkInformationVector* outputVector) override;

  double InsideFrom = 1.0;
  double SmoothingSigmaVoxels = 0.0;

private:
  vtkLabelIsosurfaceFilter(const vtkLabelIsosurfaceFilter&) = delete;
  void operator=(const vtkLabelIsosurfaceFilter&) = delete;
};
