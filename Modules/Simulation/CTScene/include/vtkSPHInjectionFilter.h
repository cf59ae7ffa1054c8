// vtkSPHInjectionFilter: the one injection driver (cementsph::scene::runInjection, InjectionRunner.h) as a VTK
// image filter, so that reader -> threshold -> injection -> isosurface -> surface distance is a pipeline of
// SetInputConnection calls (Examples/cpp/InjectionPipeline.cxx).
//
// Input port 0 (required): the CT, vtkImageData (HU in the first scalar component, any scalar type; mm
//   geometry in the CT's patient frame, LPS; any direction matrix: AxisAlignedCT.h).
// Input port 1 (optional): a bone mask on the SAME grid (same dimensions; non-zero = bone), e.g. a
//   vtkImageThreshold of the CT or a segmentation from 3D Slicer. No engine reads it (they build their solid
//   from the CT's HU and the scene's threshold_hu / bone model): it only adds to the label map's leaked class
//   (output 1): cement in a voxel the mask marks 0 is leaked. Not on the input's grid: an error (one line).
// Output port 0: the simulated CT, float vtkImageData on the INPUT's grid (its extent, origin, spacing and
//   direction): the input's HU outside the region of interest, inside it the input's HU plus the change the
//   injection made (k rho_fluid / rho0), taken through physical points from the driver's simulated CT on the
//   axis-aligned grid (InputGridPaste.h: exact for axial, flipped and axis-swapped CTs, interpolated for
//   oblique ones). The simulated CT minus the input is therefore the injection's change voxel by voxel.
// Output port 1: the cement label map, unsigned char vtkImageData on the input's grid: 0 no cement, 1 cement,
//   2 leaked cement. From an engine that labels its cement (InjectionModel::cementLabels; the voxel-grid Darcy
//   engine: 1 where a voxel's pores are at least half filled, 2 any cement outside bone by its soft-tissue
//   rule) those labels, each input voxel taking the region voxel nearest its centre: the same map as
//   cement_labels.nrrd (exact for axial and reoriented CTs). From an engine without labels (particles): 1
//   where the simulated CT rose by at least k/2 (cement density at least half rho0, the threshold the
//   phantom's cement uses), 2 there where the engine assessed leakage (continuum bone) and the voxel is soft
//   tissue by the scene's HU rule (BoneCalibration.h). With a bone mask (input 1): cement (1) in a voxel the
//   mask marks 0 is leaked (2).
// Output port 2: the cement as points, vtkPolyData (mm, the CT's frame): the particles of a particle engine
//   (velocity_m_per_s, density_kg_per_m3, pressure_pa, age_s, ...) or one point per voxel holding cement
//   (fill_fraction, cement_volume_mm3, ...), InjectionModel::cement().
// ProduceImageOutputs (on by default) off: outputs 0 and 1 stay empty, so a run costs no pass over the whole
//   input grid (the paste-back and the label map: tens of millions of voxels on a clinical CT, per run). For a
//   caller that reads only the typed result and the cement points (plan's evaluations, InjectionPlanner.cpp).
// The typed result (GetResult(): summary, tip-pressure series, the region's images, the anatomy labels, ...) is
//   kept after each run, so a caller reads the run, not the files it wrote.
// Parameters: the scene's values by typed setters (SetScene sets all of them at once, including the
// viscosity table, integrator, bone and model overrides that have no setter of their own). OutputDirectory
// non-empty: the driver's files (metrics.json, simulated_ct.nrrd on the region, ...) are written there too.
// Progress: UpdateProgress (ProgressEvent) as simulated time advances; SetAbortExecute(1) from an observer
// stops the run at the next report (the outputs then hold the run so far, metrics say stopped_early).
// Errors (bad scene, tip in solid, unstable run, a mask on another grid): RequestData leaves the outputs
// empty, fires ErrorEvent with the message (no VTK error print), and keeps it: GetErrorMessage(),
// RethrowIfFailed().
#pragma once

#include "cementsph/scene/InjectionModel.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/scene/SceneConfig.h"

#include <vtkImageAlgorithm.h>

#include <exception>
#include <functional>
#include <optional>
#include <string>
#include <utility>

class vtkAlgorithmOutput;
class vtkImageData;
class vtkPolyData;

class vtkSPHInjectionFilter : public vtkImageAlgorithm {
public:
  static vtkSPHInjectionFilter* New();
  vtkTypeMacro(vtkSPHInjectionFilter, vtkImageAlgorithm)
  void PrintSelf(ostream& os, vtkIndent indent) override;

  // The output ports.
  enum OutputPort { SimulatedCTPort = 0, LabelMapPort = 1, CementPointsPort = 2 };
  // The label map's values (output 1).
  enum Label : unsigned char { NoCement = 0, Cement = 1, LeakedCement = 2 };

  // The optional bone mask (input port 1).
  void SetBoneMaskConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetBoneMaskData(vtkDataObject* mask) { this->SetInputData(1, mask); }

  vtkSetVector3Macro(TipMm, double);
  vtkGetVector3Macro(TipMm, double);
  // Setting a direction (even the default +z) counts as giving one: a patient CT needs one (issue 20).
  void SetDirection(double x, double y, double z);
  void SetDirection(const double d[3]) { this->SetDirection(d[0], d[1], d[2]); }
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
  // Off: no simulated CT nor label map on the input grid (outputs 0 and 1 empty); the result and points as ever.
  vtkSetMacro(ProduceImageOutputs, bool);
  vtkGetMacro(ProduceImageOutputs, bool);
  vtkBooleanMacro(ProduceImageOutputs, bool);
  void SetOutputDirectory(const std::string& dir);
  // Each frame of the CT series as the run makes it (InjectionRunOptions::onCtFrame: simulated_ct_snapshots, with an
  // OutputDirectory). Observes the run without changing its outputs, so setting it does not rerun the filter.
  void SetCtFrameObserver(std::function<void(double timeS, const cementsph::imaging::ImageType& frame)> observer) {
    this->CtFrameObserver = std::move(observer);
  }
  const std::string& GetOutputDirectory() const { return this->OutputDirectory; }

  // All of a scene's values (the setters above then read them back).
  void SetScene(const cementsph::scene::SceneConfig& scene);
  cementsph::scene::SceneConfig GetScene() const;

  vtkImageData* GetSimulatedCTOutput();
  vtkImageData* GetLabelMapOutput();
  vtkPolyData* GetCementPointsOutput();
  vtkPolyData* GetParticlesOutput() { return this->GetCementPointsOutput(); } // the name before the rework
  // metrics.json of the last run ("" before one, or after a failed one).
  const std::string& GetMetricsJSON() const { return this->MetricsJSON; }
  // The typed result of the last successful run (InjectionRunner.h: the driver's InjectionRunResult, metrics
  // as metrics.json holds them, the outlet's time series, the region's simulated CT and labels, the images the
  // files hold); nullptr before one, or after a failed one.
  const cementsph::scene::InjectionRunResult* GetResult() const { return this->Result ? &*this->Result : nullptr; }
  // Its summary (InjectionModel.h); nullptr as GetResult().
  const cementsph::scene::InjectionSummary* GetSummary() const { return this->Result ? &this->Result->summary : nullptr; }
  const std::string& GetErrorMessage() const { return this->ErrorMessage; }
  void RethrowIfFailed() const;

protected:
  vtkSPHInjectionFilter();
  ~vtkSPHInjectionFilter() override = default;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation* request, vtkInformationVector** inputVector,
                         vtkInformationVector* outputVector) override;
  int RequestUpdateExtent(vtkInformation* request, vtkInformationVector** inputVector,
                          vtkInformationVector* outputVector) override;
  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                  vtkInformationVector* outputVector) override;

  double TipMm[3] = {0, 0, 0};
  double Direction[3] = {0, 0, 1};
  bool DirectionGiven = false; // SetDirection was called, or SetScene brought a given direction
  double ParticleRadiusMm, CannulaInnerDiameterMm, CannulaLengthMm, FlowRateMlPerS, VolumeMl, ViscosityPaS,
      ThresholdHU, ROISizeMm, SnapshotIntervalS, SolidMassFactor;
  bool CannulaWall;
  double HUPerRelativeDensity = 3000.0;
  bool PrintProgress = false;
  bool ProduceImageOutputs = true;
  std::string OutputDirectory;
  std::function<void(double, const cementsph::imaging::ImageType&)> CtFrameObserver;
  cementsph::scene::SceneConfig Base; // the values without a setter of their own
  std::string MetricsJSON, ErrorMessage;
  std::optional<cementsph::scene::InjectionRunResult> Result;
  std::exception_ptr Error;
  // The input as the driver takes it (an ITK copy), kept while the input is the same object with the same
  // modification time: a plan runs dozens of injections on one CT, and the copy is a pass over every voxel.
  // Held as long as the filter (one scan's worth of float voxels).
  cementsph::imaging::ImageType::Pointer InputCopy;
  const vtkImageData* InputCopySource = nullptr;
  vtkMTimeType InputCopyTime = 0;

  // Outputs 0 and 1 from the run (the rules are above, output ports 0 and 1).
  void FillImageOutputs(vtkImageData* input, vtkImageData* mask, const cementsph::imaging::ImageType* ct,
                        const cementsph::scene::InjectionRunResult& r, const cementsph::scene::SceneConfig& scene,
                        vtkImageData* simulated, vtkImageData* labels) const;
  const cementsph::imaging::ImageType* InputAsItk(vtkImageData* input);

private:
  vtkSPHInjectionFilter(const vtkSPHInjectionFilter&) = delete;
  void operator=(const vtkSPHInjectionFilter&) = delete;
};
