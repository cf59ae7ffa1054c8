// vtkAffineRegistrationFilter: a post-injection CT registered onto the pre-injection CT
// (cementsph/imaging/AffineRegistration.h: translation, rigid, then affine stages, mean squares, the cement
// masked out of the metric) and resampled onto the pre CT's grid, so that it can be thresholded and compared
// with the simulation voxel by voxel (what `cementsph compare` does first).
// Input port 0: the fixed image (pre CT, HU). Input port 1: the moving image (post CT, HU).
// Output: float vtkImageData on the fixed image's grid, the moving image resampled (linear; -1024 HU outside).
// GetMatrix(): the 4x4 transform that maps fixed points to moving points (mm, LPS).
// Errors: as vtkSPHInjectionFilter (empty output, ErrorEvent, GetErrorMessage, RethrowIfFailed).
#pragma once

#include "cementsph/pipeline/FilterError.h"

#include <vtkImageAlgorithm.h>
#include <vtkNew.h>

class vtkMatrix4x4;

class vtkAffineRegistrationFilter : public vtkImageAlgorithm {
public:
  static vtkAffineRegistrationFilter* New();
  vtkTypeMacro(vtkAffineRegistrationFilter, vtkImageAlgorithm)
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetFixedConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(0, output); }
  void SetMovingConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }

  vtkMatrix4x4* GetMatrix() { return this->Matrix; }
  // Mean squares [HU^2] at the end, and the wall time [s] of the last registration.
  vtkGetMacro(FinalMetric, double);
  vtkGetMacro(Seconds, double);
  const std::string& GetErrorMessage() const { return this->Error.message(); }
  void RethrowIfFailed() const { this->Error.rethrow(); }

protected:
  vtkAffineRegistrationFilter();
  ~vtkAffineRegistrationFilter() override = default;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestUpdateExtent(vtkInformation* request, vtkInformationVector** inputVector,
                          vtkInformationVector* outputVector) override;
  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                  vtkInformationVector* outputVector) override;

  vtkNew<vtkMatrix4x4> Matrix;
  double FinalMetric = 0.0, Seconds = 0.0;
  cementsph::pipeline::FilterError Error;

private:
  vtkAffineRegistrationFilter(const vtkAffineRegistrationFilter&) = delete;
  void operator=(const vtkAffineRegistrationFilter&) = delete;
};
