#include "cementsph/pipeline/vtkCementSPHImageReader.h"

#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMatrix3x3.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkStreamingDemandDrivenPipeline.h>

#include <stdexcept>

vtkStandardNewMacro(vtkCementSPHImageReader);

vtkCementSPHImageReader::vtkCementSPHImageReader() {
  this->SetNumberOfInputPorts(0);
  this->SetNumberOfOutputPorts(1);
}

void vtkCementSPHImageReader::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << this->FileName << "\n";
}

void vtkCementSPHImageReader::SetFileName(const std::string& path) {
  if (path == this->FileName) return;
  this->FileName = path;
  this->Modified();
}

int vtkCementSPHImageReader::RequestInformation(vtkInformation*, vtkInformationVector**,
                                                vtkInformationVector* outputVector) {
  vtkInformation* out = outputVector->GetInformationObject(0);
  if (!this->Volume || this->VolumeTime < this->GetMTime()) {
    this->Error.clear();
    this->Volume = nullptr;
    this->VolumeTime = this->GetMTime();
    try {
      if (this->FileName.empty()) throw std::invalid_argument("vtkCementSPHImageReader: no file name set");
      this->Volume = cementsph::imaging::toVtk(cementsph::imaging::readVolume(this->FileName));
      this->Volume->GetPointData()->GetScalars()->SetName("hu");
    } catch (const std::exception&) {
      this->Error.keepCurrent(this);
    }
  }
  if (!this->Volume) {
    // Nothing to describe: an empty extent, so the pipeline runs on and the next filter says what it lacks.
    const int empty[6] = {0, -1, 0, -1, 0, -1};
    out->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), empty, 6);
    return 1;
  }
  out->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), this->Volume->GetExtent(), 6);
  out->Set(vtkDataObject::SPACING(), this->Volume->GetSpacing(), 3);
  out->Set(vtkDataObject::ORIGIN(), this->Volume->GetOrigin(), 3);
  out->Set(vtkDataObject::DIRECTION(), this->Volume->GetDirectionMatrix()->GetData(), 9);
  vtkDataObject::SetPointDataActiveScalarInfo(out, VTK_FLOAT, 1);
  return 1;
}

int vtkCementSPHImageReader::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector) {
  vtkImageData* output = vtkImageData::GetData(outputVector, 0);
  output->Initialize();
  if (this->Volume) output->ShallowCopy(this->Volume);
  return 1;
}
