#include "cementsph/pipeline/vtkAffineRegistrationFilter.h"

#include "cementsph/imaging/AffineRegistration.h"
#include "cementsph/imaging/ItkVtkBridge.h"

#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMatrix4x4.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkStreamingDemandDrivenPipeline.h>

#include <stdexcept>

vtkStandardNewMacro(vtkAffineRegistrationFilter);

vtkAffineRegistrationFilter::vtkAffineRegistrationFilter() {
  this->SetNumberOfInputPorts(2);
  this->SetNumberOfOutputPorts(1);
}

void vtkAffineRegistrationFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FinalMetric: " << this->FinalMetric << "\n";
}

int vtkAffineRegistrationFilter::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  return 1;
}

int vtkAffineRegistrationFilter::RequestUpdateExtent(vtkInformation*, vtkInformationVector** inputVector,
                                                     vtkInformationVector*) {
  // Both whole volumes: registration samples anywhere in them. (The output's information, the fixed grid,
  // is the executive's default copy of input 0's.)
  using SDDP = vtkStreamingDemandDrivenPipeline;
  for (int port = 0; port < 2; ++port) {
    vtkInformation* in = inputVector[port]->GetInformationObject(0);
    if (in && in->Has(SDDP::WHOLE_EXTENT())) {
      in->Set(SDDP::UPDATE_EXTENT(), in->Get(SDDP::WHOLE_EXTENT()), 6);
      in->Set(SDDP::EXACT_EXTENT(), 1);
    }
  }
  return 1;
}

int vtkAffineRegistrationFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                             vtkInformationVector* outputVector) {
  vtkImageData* fixed = vtkImageData::GetData(inputVector[0]);
  vtkImageData* moving = vtkImageData::GetData(inputVector[1]);
  vtkImageData* output = vtkImageData::GetData(outputVector, 0);
  this->Error.clear();
  output->Initialize();
  this->Matrix->Identity();
  try {
    if (!fixed || !fixed->GetPointData()->GetScalars())
      throw std::invalid_argument("vtkAffineRegistrationFilter: no fixed (pre) image on input port 0");
    if (!moving || !moving->GetPointData()->GetScalars())
      throw std::invalid_argument("vtkAffineRegistrationFilter: no moving (post) image on input port 1");
    const auto f = cementsph::imaging::imageFromVtk(fixed);
    const auto m = cementsph::imaging::imageFromVtk(moving);
    const auto r = cementsph::imaging::registerAffine(f, m);
    const auto resampled = cementsph::imaging::resampleOnto(m, f, r.transform);
    // The affine transform x -> A x + t (ITK keeps it as matrix, centre and translation; GetOffset is t).
    const auto a = r.transform->GetMatrix();
    const auto t = r.transform->GetOffset();
    for (unsigned i = 0; i < 3; ++i) {
      for (unsigned j = 0; j < 3; ++j) this->Matrix->SetElement(int(i), int(j), a(i, j));
      this->Matrix->SetElement(int(i), 3, t[i]);
    }
    this->FinalMetric = r.finalMetric;
    this->Seconds = r.seconds;
    output->ShallowCopy(cementsph::imaging::toVtk(resampled));
    output->SetExtent(fixed->GetExtent());
  } catch (const std::exception&) {
    output->Initialize();
    this->Error.keepCurrent(this);
  }
  return 1;
}
