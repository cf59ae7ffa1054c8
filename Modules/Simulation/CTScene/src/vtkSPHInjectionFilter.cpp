#include "vtkSPHInjectionFilter.h"

#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/scene/InputGridPaste.h"

#include <vtkCommand.h>
#include <vtkDataObject.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStreamingDemandDrivenPipeline.h>

#include <stdexcept>

vtkStandardNewMacro(vtkSPHInjectionFilter);

vtkSPHInjectionFilter::vtkSPHInjectionFilter() {
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(2);
  this->SetScene(cementsph::scene::scenePreset("paper"));
}

void vtkSPHInjectionFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Scene: " << cementsph::scene::toJson(this->GetScene()).dump() << "\n";
  os << indent << "OutputDirectory: " << this->OutputDirectory << "\n";
}

void vtkSPHInjectionFilter::SetOutputDirectory(const std::string& dir) {
  if (dir == this->OutputDirectory) return;
  this->OutputDirectory = dir;
  this->Modified();
}

void vtkSPHInjectionFilter::SetScene(const cementsph::scene::SceneConfig& s) {
  this->Base = s;
  if (s.tipMm) {
    for (int a = 0; a < 3; ++a) this->TipMm[a] = (*s.tipMm)[a];
  }
  for (int a = 0; a < 3; ++a) this->Direction[a] = s.direction[a];
  this->ParticleRadiusMm = s.particleRadiusMm;
  this->CannulaInnerDiameterMm = s.cannulaInnerDiameterMm;
  this->CannulaLengthMm = s.cannulaLengthMm;
  this->CannulaWall = s.cannulaWall;
  this->FlowRateMlPerS = s.flowRateMlPerS;
  this->VolumeMl = s.volumeMl;
  this->ViscosityPaS = s.viscosityPaS;
  this->ThresholdHU = s.thresholdHu;
  this->ROISizeMm = s.roiSizeMm;
  this->SnapshotIntervalS = s.snapshotIntervalS;
  this->SolidMassFactor = s.solidMassFactor;
  this->Modified();
}

cementsph::scene::SceneConfig vtkSPHInjectionFilter::GetScene() const {
  cementsph::scene::SceneConfig s = this->Base;
  s.tipMm = Eigen::Vector3d(this->TipMm[0], this->TipMm[1], this->TipMm[2]);
  s.direction = Eigen::Vector3d(this->Direction[0], this->Direction[1], this->Direction[2]);
  s.particleRadiusMm = this->ParticleRadiusMm;
  s.cannulaInnerDiameterMm = this->CannulaInnerDiameterMm;
  s.cannulaLengthMm = this->CannulaLengthMm;
  s.cannulaWall = this->CannulaWall;
  s.flowRateMlPerS = this->FlowRateMlPerS;
  s.volumeMl = this->VolumeMl;
  s.viscosityPaS = this->ViscosityPaS;
  s.thresholdHu = this->ThresholdHU;
  s.roiSizeMm = this->ROISizeMm;
  s.snapshotIntervalS = this->SnapshotIntervalS;
  s.solidMassFactor = this->SolidMassFactor;
  return s;
}

vtkPolyData* vtkSPHInjectionFilter::GetParticlesOutput() {
  return vtkPolyData::SafeDownCast(this->GetOutputDataObject(0));
}
vtkImageData* vtkSPHInjectionFilter::GetSimulatedCTOutput() {
  return vtkImageData::SafeDownCast(this->GetOutputDataObject(1));
}

void vtkSPHInjectionFilter::RethrowIfFailed() const {
  if (this->Error) std::rethrow_exception(this->Error);
}

int vtkSPHInjectionFilter::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  return 1;
}

int vtkSPHInjectionFilter::FillOutputPortInformation(int port, vtkInformation* info) {
  info->Set(vtkDataObject::DATA_TYPE_NAME(), port == 0 ? "vtkPolyData" : "vtkImageData");
  return 1;
}

vtkTypeBool vtkSPHInjectionFilter::ProcessRequest(vtkInformation* request, vtkInformationVector** inputVector,
                                                  vtkInformationVector* outputVector) {
  if (request->Has(vtkDemandDrivenPipeline::REQUEST_INFORMATION()))
    return this->RequestInformation(inputVector, outputVector);
  if (request->Has(vtkStreamingDemandDrivenPipeline::REQUEST_UPDATE_EXTENT()))
    return this->RequestUpdateExtent(inputVector);
  if (request->Has(vtkDemandDrivenPipeline::REQUEST_DATA())) return this->RequestData(inputVector, outputVector);
  return this->Superclass::ProcessRequest(request, inputVector, outputVector);
}

int vtkSPHInjectionFilter::RequestInformation(vtkInformationVector** inputVector, vtkInformationVector* outputVector) {
  // The simulated CT lies on the input's grid.
  vtkInformation* in = inputVector[0]->GetInformationObject(0);
  vtkInformation* out = outputVector->GetInformationObject(1);
  using SDDP = vtkStreamingDemandDrivenPipeline;
  if (in->Has(SDDP::WHOLE_EXTENT())) out->CopyEntry(in, SDDP::WHOLE_EXTENT());
  if (in->Has(vtkDataObject::SPACING())) out->CopyEntry(in, vtkDataObject::SPACING());
  if (in->Has(vtkDataObject::ORIGIN())) out->CopyEntry(in, vtkDataObject::ORIGIN());
  if (in->Has(vtkDataObject::DIRECTION())) out->CopyEntry(in, vtkDataObject::DIRECTION());
  vtkDataObject::SetPointDataActiveScalarInfo(out, VTK_FLOAT, 1);
  return 1;
}

int vtkSPHInjectionFilter::RequestUpdateExtent(vtkInformationVector** inputVector) {
  // The whole CT, whatever piece of the outputs was asked for.
  vtkInformation* in = inputVector[0]->GetInformationObject(0);
  using SDDP = vtkStreamingDemandDrivenPipeline;
  if (in->Has(SDDP::WHOLE_EXTENT())) {
    in->Set(SDDP::UPDATE_EXTENT(), in->Get(SDDP::WHOLE_EXTENT()), 6);
    in->Set(SDDP::EXACT_EXTENT(), 1);
  }
  return 1;
}

int vtkSPHInjectionFilter::RequestData(vtkInformationVector** inputVector, vtkInformationVector* outputVector) {
  vtkImageData* input = vtkImageData::GetData(inputVector[0]);
  vtkPolyData* particles = vtkPolyData::GetData(outputVector, 0);
  vtkImageData* simulated = vtkImageData::GetData(outputVector, 1);
  this->Error = nullptr;
  this->ErrorMessage.clear();
  this->MetricsJSON.clear();
  particles->Initialize();
  simulated->Initialize();
  try {
    if (!input || !input->GetPointData()->GetScalars()) throw std::invalid_argument("vtkSPHInjectionFilter: no CT on the input");
    const auto ct = cementsph::imaging::imageFromVtk(input);
    cementsph::scene::InjectionRunOptions o;
    o.outDir = this->OutputDirectory;
    o.huPerRelativeDensity = this->HUPerRelativeDensity;
    o.progress = this->PrintProgress;
    o.onProgress = [this](double fraction) {
      this->UpdateProgress(fraction);
      return !this->GetAbortExecute();
    };
    this->UpdateProgress(0.0);
    const auto r = cementsph::scene::runInjection(ct, this->GetScene(), o);
    this->MetricsJSON = r.metrics.dump(2);
    particles->ShallowCopy(r.particles);
    // The whole input grid: the input's HU with the simulated region of interest pasted in. The runner's
    // simulated CT lies on the AXIS-ALIGNED CT's grid (a reorientation or resampling when the input's
    // direction is not the identity), so it goes back through physical points, not through its indices.
    const auto background = cementsph::scene::alignedBackgroundOn(ct, r.simulatedCt);
    const auto full = cementsph::scene::pasteOntoInputGrid(ct, r.simulatedCt, background);
    vtkSmartPointer<vtkImageData> image = cementsph::imaging::toVtk(full);
    simulated->ShallowCopy(image);
    // Keep the input's extent labelling (same size).
    simulated->SetExtent(input->GetExtent());
    simulated->SetOrigin(input->GetOrigin());
    simulated->SetSpacing(input->GetSpacing());
    simulated->SetDirectionMatrix(input->GetDirectionMatrix());
    this->UpdateProgress(1.0);
  } catch (const std::exception& e) {
    this->Error = std::current_exception();
    this->ErrorMessage = e.what();
    particles->Initialize();
    simulated->Initialize();
    this->InvokeEvent(vtkCommand::ErrorEvent, const_cast<char*>(this->ErrorMessage.c_str()));
  }
  return 1;
}
