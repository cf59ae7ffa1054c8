#include "vtkSPHInjectionFilter.h"

#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/scene/InputGridPaste.h"

#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkDataObject.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStreamingDemandDrivenPipeline.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

vtkStandardNewMacro(vtkSPHInjectionFilter);

namespace {

using SDDP = vtkStreamingDemandDrivenPipeline;

// The cement label map on the input's grid (the rules are in the header, output port 1).
vtkSmartPointer<vtkImageData> cementLabels(vtkImageData* input, const cementsph::imaging::ImageType* ct,
                                           const cementsph::imaging::ImageType* simulated,
                                           const cementsph::scene::InjectionResult& r, vtkImageData* mask,
                                           const cementsph::scene::SceneConfig& scene, double huPerRelativeDensity) {
  auto labels = vtkSmartPointer<vtkImageData>::New();
  labels->SetExtent(input->GetExtent());
  labels->SetOrigin(input->GetOrigin());
  labels->SetSpacing(input->GetSpacing());
  labels->SetDirectionMatrix(input->GetDirectionMatrix());
  labels->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  labels->GetPointData()->GetScalars()->SetName("cement_labels");
  auto* l = static_cast<std::uint8_t*>(labels->GetScalarPointer());
  const vtkIdType count = labels->GetNumberOfPoints();
  std::fill(l, l + count, std::uint8_t(vtkSPHInjectionFilter::NoCement));
  // ITK's buffers and VTK's points share one order (x fastest), all over the input's whole grid.
  const float* hu = ct->GetBufferPointer();
  if (const cementsph::imaging::MaskType* file = r.cementLabelsFile;
      file && file->GetLargestPossibleRegion() == ct->GetLargestPossibleRegion()) {
    // The engine's labels as the driver wrote them on the input grid (cement_labels.nrrd).
    std::copy(file->GetBufferPointer(), file->GetBufferPointer() + count, l);
  } else if (const cementsph::imaging::MaskType* region = r.cementLabels) {
    // The engine's labels on the (axis-aligned) region: each input voxel takes the region voxel nearest its
    // centre (labels are not interpolated), as the driver's file does; exact for axial and reoriented CTs.
    int extent[6];
    input->GetExtent(extent);
    vtkIdType i = 0;
    for (int z = extent[4]; z <= extent[5]; ++z)
      for (int y = extent[2]; y <= extent[3]; ++y)
        for (int x = extent[0]; x <= extent[1]; ++x, ++i) {
          double centre[3];
          input->TransformContinuousIndexToPhysicalPoint(x, y, z, centre);
          cementsph::imaging::MaskType::PointType p;
          for (unsigned a = 0; a < 3; ++a) p[a] = centre[a];
          cementsph::imaging::MaskType::IndexType index;
          if (region->TransformPhysicalPointToIndex(p, index)) l[i] = region->GetPixel(index);
        }
  } else {
    // An engine without labels (particles): the simulated CT rose by at least k/2 (cement at half its rest
    // density or more); leaked where the engine assessed leakage and the voxel is soft tissue (its HU rule).
    const float* sim = simulated->GetBufferPointer();
    const double rise = 0.5 * huPerRelativeDensity;
    for (vtkIdType i = 0; i < count; ++i)
      if (double(sim[i]) - double(hu[i]) >= rise)
        l[i] = r.summary.leakageAssessed &&
                       scene.bone.tissue(double(hu[i])) == cementsph::scene::BoneCalibration::Tissue::SoftTissue
                   ? vtkSPHInjectionFilter::LeakedCement
                   : vtkSPHInjectionFilter::Cement;
  }
  // The bone mask: cement in a voxel it marks 0 is leaked.
  if (vtkDataArray* m = mask ? mask->GetPointData()->GetScalars() : nullptr)
    for (vtkIdType i = 0; i < count; ++i)
      if (l[i] == vtkSPHInjectionFilter::Cement && m->GetComponent(i, 0) == 0.0) l[i] = vtkSPHInjectionFilter::LeakedCement;
  return labels;
}

bool sameGrid(vtkImageData* a, vtkImageData* b) {
  int ea[6], eb[6];
  a->GetExtent(ea);
  b->GetExtent(eb);
  for (int i = 0; i < 3; ++i)
    if (ea[2 * i + 1] - ea[2 * i] != eb[2 * i + 1] - eb[2 * i]) return false;
  // The same voxel centres to a thousandth of a voxel: a mask resampled elsewhere is another grid.
  double pa[3], pb[3];
  a->TransformContinuousIndexToPhysicalPoint(ea[0], ea[2], ea[4], pa);
  b->TransformContinuousIndexToPhysicalPoint(eb[0], eb[2], eb[4], pb);
  const double* s = a->GetSpacing();
  const double* t = b->GetSpacing();
  for (int i = 0; i < 3; ++i)
    if (std::abs(pa[i] - pb[i]) > 1e-3 * s[i] || std::abs(s[i] - t[i]) > 1e-6 * s[i]) return false;
  return true;
}

} // namespace

vtkSPHInjectionFilter::vtkSPHInjectionFilter() {
  this->SetNumberOfInputPorts(2);
  this->SetNumberOfOutputPorts(3);
  this->SetScene(cementsph::scene::scenePreset("paper"));
}

void vtkSPHInjectionFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Scene: " << cementsph::scene::toJson(this->GetScene()).dump() << "\n";
  os << indent << "OutputDirectory: " << this->OutputDirectory << "\n";
  os << indent << "ProduceImageOutputs: " << this->ProduceImageOutputs << "\n";
}

void vtkSPHInjectionFilter::SetOutputDirectory(const std::string& dir) {
  if (dir == this->OutputDirectory) return;
  this->OutputDirectory = dir;
  this->Modified();
}

void vtkSPHInjectionFilter::SetDirection(double x, double y, double z) {
  this->DirectionGiven = true;
  if (this->Direction[0] == x && this->Direction[1] == y && this->Direction[2] == z) return;
  this->Direction[0] = x;
  this->Direction[1] = y;
  this->Direction[2] = z;
  this->Modified();
}

void vtkSPHInjectionFilter::SetScene(const cementsph::scene::SceneConfig& s) {
  this->Base = s;
  if (s.tipMm) {
    for (int a = 0; a < 3; ++a) this->TipMm[a] = (*s.tipMm)[a];
  }
  for (int a = 0; a < 3; ++a) this->Direction[a] = s.direction[a];
  this->DirectionGiven = s.directionGiven();
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
  if (this->DirectionGiven) s.explicitKeys.insert("direction");
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

vtkImageData* vtkSPHInjectionFilter::GetSimulatedCTOutput() {
  return vtkImageData::SafeDownCast(this->GetOutputDataObject(SimulatedCTPort));
}
vtkImageData* vtkSPHInjectionFilter::GetLabelMapOutput() {
  return vtkImageData::SafeDownCast(this->GetOutputDataObject(LabelMapPort));
}
vtkPolyData* vtkSPHInjectionFilter::GetCementPointsOutput() {
  return vtkPolyData::SafeDownCast(this->GetOutputDataObject(CementPointsPort));
}

void vtkSPHInjectionFilter::RethrowIfFailed() const {
  if (this->Error) std::rethrow_exception(this->Error);
}

int vtkSPHInjectionFilter::FillInputPortInformation(int port, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  if (port == 1) info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

int vtkSPHInjectionFilter::FillOutputPortInformation(int port, vtkInformation* info) {
  info->Set(vtkDataObject::DATA_TYPE_NAME(), port == CementPointsPort ? "vtkPolyData" : "vtkImageData");
  return 1;
}

int vtkSPHInjectionFilter::RequestInformation(vtkInformation*, vtkInformationVector** inputVector,
                                              vtkInformationVector* outputVector) {
  // The simulated CT and the label map lie on the input's grid; the points have no extent.
  vtkInformation* in = inputVector[0]->GetInformationObject(0);
  for (int port : {int(SimulatedCTPort), int(LabelMapPort)}) {
    vtkInformation* out = outputVector->GetInformationObject(port);
    for (auto* key : {SDDP::WHOLE_EXTENT()})
      if (in->Has(key)) out->CopyEntry(in, key);
    for (auto* key : {vtkDataObject::SPACING(), vtkDataObject::ORIGIN(), vtkDataObject::DIRECTION()})
      if (in->Has(key)) out->CopyEntry(in, key);
    vtkDataObject::SetPointDataActiveScalarInfo(out, port == SimulatedCTPort ? VTK_FLOAT : VTK_UNSIGNED_CHAR, 1);
  }
  // The executive copied the input's image keys to every output; a polydata output has none.
  vtkInformation* points = outputVector->GetInformationObject(CementPointsPort);
  points->Remove(SDDP::WHOLE_EXTENT());
  points->Remove(vtkDataObject::SPACING());
  points->Remove(vtkDataObject::ORIGIN());
  points->Remove(vtkDataObject::DIRECTION());
  return 1;
}

int vtkSPHInjectionFilter::RequestUpdateExtent(vtkInformation*, vtkInformationVector** inputVector,
                                               vtkInformationVector*) {
  // The whole CT (and mask), whatever piece of the outputs was asked for: the run needs all of it.
  for (int port = 0; port < 2; ++port)
    for (int c = 0; c < inputVector[port]->GetNumberOfInformationObjects(); ++c) {
      vtkInformation* in = inputVector[port]->GetInformationObject(c);
      if (in->Has(SDDP::WHOLE_EXTENT())) {
        in->Set(SDDP::UPDATE_EXTENT(), in->Get(SDDP::WHOLE_EXTENT()), 6);
        in->Set(SDDP::EXACT_EXTENT(), 1);
      }
    }
  return 1;
}

const cementsph::imaging::ImageType* vtkSPHInjectionFilter::InputAsItk(vtkImageData* input) {
  if (!this->InputCopy || this->InputCopySource != input || this->InputCopyTime != input->GetMTime()) {
    this->InputCopy = nullptr; // the old copy goes before the new one is made: one scan's copy at a time
    this->InputCopy = cementsph::imaging::imageFromVtk(input);
    this->InputCopySource = input;
    this->InputCopyTime = input->GetMTime();
  }
  return this->InputCopy.GetPointer();
}

void vtkSPHInjectionFilter::FillImageOutputs(vtkImageData* input, vtkImageData* mask,
                                             const cementsph::imaging::ImageType* ct,
                                             const cementsph::scene::InjectionRunResult& r,
                                             const cementsph::scene::SceneConfig& scene, vtkImageData* simulated,
                                             vtkImageData* labels) const {
  // The whole input grid: the input's HU with the simulated region of interest pasted in. The driver's
  // simulated CT lies on the AXIS-ALIGNED CT's grid (a reorientation or resampling when the input's
  // direction is not the identity), so it goes back through physical points, not through its indices.
  // The driver made it already where it wrote files on the input's grid (simulated_ct.nrrd): that image, not a
  // second paste (on a whole-scan region the paste and its background were two more copies of the scan).
  cementsph::imaging::ImageType::Pointer full = r.simulatedCtFile;
  if (!full || full->GetLargestPossibleRegion() != ct->GetLargestPossibleRegion()) {
    const auto background = cementsph::scene::alignedBackgroundOn(ct, r.simulatedCt);
    full = cementsph::scene::pasteOntoInputGrid(ct, r.simulatedCt, background);
  }
  vtkSmartPointer<vtkImageData> image = cementsph::imaging::toVtk(full);
  vtkSmartPointer<vtkImageData> labelMap = cementLabels(input, ct, full, r, mask, scene, this->HUPerRelativeDensity);
  simulated->ShallowCopy(image);
  simulated->GetPointData()->GetScalars()->SetName("simulated_ct_hu");
  // The input's own extent numbering (toVtk starts at 0; a cropped reader's output need not).
  simulated->SetExtent(input->GetExtent());
  simulated->SetOrigin(input->GetOrigin());
  simulated->SetSpacing(input->GetSpacing());
  simulated->SetDirectionMatrix(input->GetDirectionMatrix());
  labels->ShallowCopy(labelMap);
}

int vtkSPHInjectionFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                       vtkInformationVector* outputVector) {
  vtkImageData* input = vtkImageData::GetData(inputVector[0]);
  vtkImageData* mask = inputVector[1]->GetNumberOfInformationObjects() ? vtkImageData::GetData(inputVector[1]) : nullptr;
  vtkImageData* simulated = vtkImageData::GetData(outputVector, SimulatedCTPort);
  vtkImageData* labels = vtkImageData::GetData(outputVector, LabelMapPort);
  vtkPolyData* points = vtkPolyData::GetData(outputVector, CementPointsPort);
  this->Error = nullptr;
  this->ErrorMessage.clear();
  this->MetricsJSON.clear();
  this->Result.reset();
  simulated->Initialize();
  labels->Initialize();
  points->Initialize();
  try {
    if (!input || !input->GetPointData()->GetScalars())
      throw std::invalid_argument("vtkSPHInjectionFilter: no CT on input port 0");
    if (mask && !mask->GetPointData()->GetScalars())
      throw std::invalid_argument("vtkSPHInjectionFilter: the bone mask on input port 1 has no scalars");
    if (mask && !sameGrid(input, mask))
      throw std::invalid_argument("vtkSPHInjectionFilter: the bone mask on input port 1 is not on the CT's grid "
                                  "(same dimensions, origin and spacing required)");
    const cementsph::imaging::ImageType* ct = this->InputAsItk(input);
    const cementsph::scene::SceneConfig scene = this->GetScene();
    cementsph::scene::InjectionRunOptions o;
    o.outDir = this->OutputDirectory;
    o.huPerRelativeDensity = this->HUPerRelativeDensity;
    o.progress = this->PrintProgress;
    o.onCtFrame = this->CtFrameObserver;
    o.onProgress = [this](double fraction) {
      this->UpdateProgress(fraction);
      return !this->GetAbortExecute();
    };
    this->UpdateProgress(0.0);
    cementsph::scene::InjectionRunResult r = cementsph::scene::runInjection(ct, scene, o);
    if (this->ProduceImageOutputs) this->FillImageOutputs(input, mask, ct, r, scene, simulated, labels);
    if (r.particles) points->ShallowCopy(r.particles);
    this->MetricsJSON = r.metrics.dump(2);
    this->Result = std::move(r);
    this->UpdateProgress(1.0);
  } catch (const std::exception& e) {
    this->Error = std::current_exception();
    this->ErrorMessage = e.what();
    this->MetricsJSON.clear();
    this->Result.reset();
    simulated->Initialize();
    labels->Initialize();
    points->Initialize();
    this->InvokeEvent(vtkCommand::ErrorEvent, const_cast<char*>(this->ErrorMessage.c_str()));
  }
  return 1;
}
