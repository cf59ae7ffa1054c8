// vtkSPHInjectionFilter: the inject runner (cementsph/scene/InjectionRunner.h) as a VTK algorithm.
//
// Input port 0: the CT as vtkImageData (HU scalars, mm geometry, any direction matrix: AxisAlignedCT.h).
// Output port 0: the fluid particles at the end of injection, vtkPolyData (mm; point arrays velocity_m_per_s,
//   density_kg_per_m3, pressure_pa, age_s).
// Output port 1: the simulated CT, vtkImageData on the input's full grid (its extent, origin, spacing and
//   direction): the input's HU outside the region of interest, inside it the input's HU plus the change the
//   injection made (k rho_fluid / rho0), taken through physical points from the runner's simulated CT on the
//   axis-aligned grid (InputGridPaste.h: exact for axial, flipped and axis-swapped CTs, interpolated for
//   oblique ones). The files the runner writes hold the ROI of the axis-aligned grid only.
// Parameters: the scene's values by setters (SetScene sets all of them at once, including the viscosity
// table, integrator and model overrides that have no setter of their own). OutputDirectory non-empty: the
// runner's files are written there too. Progress: UpdateProgress (ProgressEvent) as simulated time advances;
// SetAbortExecute(1) from an observer stops the run at the next report.
// Errors (bad scene, tip in solid, unstable run): RequestData leaves the outputs empty, fires ErrorEvent with
// the message (no VTK error print), and keeps it: GetErrorMessage(), RethrowIfFailed().
#pragma once

#include "cementsph/scene/SceneConfig.h"

#include <vtkAlgorithm.h>

#include <exception>
#include <string>

class vtkImageData;
class vtkPolyData;

class vtkSPHInjectionFilter : public vtkAlgorithm {
public:
  static vtkSPHInjectionFilter* New();
  vtkTypeMacro(vtkSPHInjectionFilter, vtkAlgorithm)
  void PrintSelf(ostream& os, vtkIndent indent) override;

  vtkSetVector3Macro(TipMm, double);
  vtkGetVector3Macro(TipMm, double);
  vtkSetVector3Macro(Direction, double);
  vtkGetVector3Macro(Direction, double);
  vtkSetMacro(ParticleRadiusMm, double);
  vtkGetMacro(ParticleRadiusMm, double);
  vtkSetMacro(CannulaInnerDiameterMm, double);
  vtkGetMacro(CannulaInnerDiameterMm, double);
  vtkSetMacro(CannulaLengthMm, double);
  vtkGetMacro(CannulaLengthMm, double);
  vtkSetMacro(CannulaWall, bool);
  vtkGetMacro(CannulaWall, bool);
  vtkBooleanMacro(CannulaWall, bool);
  vtkSetMacro(FlowRateMlPerS, double);
  vtkGetMacro(FlowRateMlPerS, double);
  vtkSetMacro(VolumeMl, double);
  vtkGetMacro(VolumeMl, double);
  vtkSetMacro(ViscosityPaS, double);
  vtkGetMacro(ViscosityPaS, double);
  vtkSetMacro(ThresholdHU, double);
  vtkGetMacro(ThresholdHU, double);
  vtkSetMacro(ROISizeMm, double);
  vtkGetMacro(ROISizeMm, double);
  vtkSetMacro(SnapshotIntervalS, double);
  vtkGetMacro(SnapshotIntervalS, double);
  vtkSetMacro(SolidMassFactor, double);
  vtkGetMacro(SolidMassFactor, double);
  vtkSetMacro(HUPerRelativeDensity, double);
  vtkGetMacro(HUPerRelativeDensity, double);
  vtkSetMacro(PrintProgress, bool);
  vtkGetMacro(PrintProgress, bool);
  void SetOutputDirectory(const std::string& dir);
  const std::string& GetOutputDirectory() const { return this->OutputDirectory; }

  // All of a scene's values (the setters above then read them back).
  void SetScene(const cementsph::scene::SceneConfig& scene);
  cementsph::scene::SceneConfig GetScene() const;

  vtkPolyData* GetParticlesOutput();
  vtkImageData* GetSimulatedCTOutput();
  // metrics.json of the last run ("" before one).
  const std::string& GetMetricsJSON() const { return this->MetricsJSON; }
  const std::string& GetErrorMessage() const { return this->ErrorMessage; }
  void RethrowIfFailed() const;

  vtkTypeBool ProcessRequest(vtkInformation* request, vtkInformationVector** inputVector,
                             vtkInformationVector* outputVector) override;

protected:
  vtkSPHInjectionFilter();
  ~vtkSPHInjectionFilter() override = default;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformationVector** inputVector, vtkInformationVector* outputVector);
  int RequestUpdateExtent(vtkInformationVector** inputVector);
  int RequestData(vtkInformationVector** inputVector, vtkInformationVector* outputVector);

  double TipMm[3] = {0, 0, 0};
  double Direction[3] = {0, 0, 1};
  double ParticleRadiusMm, CannulaInnerDiameterMm, CannulaLengthMm, FlowRateMlPerS, VolumeMl, ViscosityPaS,
      ThresholdHU, ROISizeMm, SnapshotIntervalS, SolidMassFactor;
  bool CannulaWall;
  double HUPerRelativeDensity = 3000.0;
  bool PrintProgress = false;
  std::string OutputDirectory;
  cementsph::scene::SceneConfig Base; // the values without a setter of their own
  std::string MetricsJSON, ErrorMessage;
  std::exception_ptr Error;

private:
  vtkSPHInjectionFilter(const vtkSPHInjectionFilter&) = delete;
  void operator=(const vtkSPHInjectionFilter&) = delete;
};
