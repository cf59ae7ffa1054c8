// vtkSurfaceDistanceFilter: the paper's surface-to-surface error (Basafa et al. 2013) between two closed
// surfaces, e.g. the simulated cement's isosurface and the experiment's (cementsph/surfacemetrics/
// SurfaceDistance.h: per-vertex point-to-triangle distances both ways, one cell locator per thread;
// vtkDistancePolyDataFilter does the same far slower).
// Input port 0: surface A (vtkPolyData, mm). Input port 1: surface B.
// Output: a copy of A with the point array DistanceToOtherSurface_mm (each vertex's distance to B).
// The figures of the last run: GetErrorMm() (the larger of the two mean distances: the paper's error),
// GetMeanAToBMm(), GetMeanBToAMm(), GetHausdorffMm(), GetHausdorff95Mm().
// Errors (a surface with no points or no cells): as vtkSPHInjectionFilter (empty output, ErrorEvent,
// GetErrorMessage, RethrowIfFailed).
#pragma once

#include "cementsph/pipeline/FilterError.h"

#include <vtkPolyDataAlgorithm.h>

class vtkSurfaceDistanceFilter : public vtkPolyDataAlgorithm {
public:
  static vtkSurfaceDistanceFilter* New();
  vtkTypeMacro(vtkSurfaceDistanceFilter, vtkPolyDataAlgorithm)
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetReferenceConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }

  vtkGetMacro(ErrorMm, double);
  vtkGetMacro(MeanAToBMm, double);
  vtkGetMacro(MeanBToAMm, double);
  vtkGetMacro(HausdorffMm, double);
  vtkGetMacro(Hausdorff95Mm, double);
  const std::string& GetErrorMessage() const { return this->Error.message(); }
  void RethrowIfFailed() const { this->Error.rethrow(); }

protected:
  vtkSurfaceDistanceFilter();
  ~vtkSurfaceDistanceFilter() override = default;
  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                  vtkInformationVector* outputVector) override;

  double ErrorMm = 0.0, MeanAToBMm = 0.0, MeanBToAMm = 0.0, HausdorffMm = 0.0, Hausdorff95Mm = 0.0;
  cementsph::pipeline::FilterError Error;

private:
  vtkSurfaceDistanceFilter(const vtkSurfaceDistanceFilter&) = delete;
  void operator=(const vtkSurfaceDistanceFilter&) = delete;
};
