#include "cementsph/pipeline/vtkSurfaceDistanceFilter.h"

#include "cementsph/surfacemetrics/SurfaceDistance.h"

#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPolyData.h>

#include <stdexcept>

vtkStandardNewMacro(vtkSurfaceDistanceFilter);

vtkSurfaceDistanceFilter::vtkSurfaceDistanceFilter() {
  this->SetNumberOfInputPorts(2);
  this->SetNumberOfOutputPorts(1);
}

void vtkSurfaceDistanceFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "ErrorMm: " << this->ErrorMm << "\n";
}

int vtkSurfaceDistanceFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                          vtkInformationVector* outputVector) {
  vtkPolyData* a = vtkPolyData::GetData(inputVector[0]);
  vtkPolyData* b = vtkPolyData::GetData(inputVector[1]);
  vtkPolyData* output = vtkPolyData::GetData(outputVector, 0);
  this->Error.clear();
  output->Initialize();
  this->ErrorMm = this->MeanAToBMm = this->MeanBToAMm = this->HausdorffMm = this->Hausdorff95Mm = 0.0;
  try {
    if (!a || !b) throw std::invalid_argument("vtkSurfaceDistanceFilter: needs a surface on each of input ports 0 and 1");
    // compareSurfaces writes the distances onto both surfaces: on copies, so the inputs stay as they are.
    vtkNew<vtkPolyData> copyA, copyB;
    copyA->ShallowCopy(a);
    copyB->ShallowCopy(b);
    const auto c = cementsph::surfacemetrics::compareSurfaces(copyA, copyB);
    this->ErrorMm = c.errorMm;
    this->MeanAToBMm = c.aToB.meanMm;
    this->MeanBToAMm = c.bToA.meanMm;
    this->HausdorffMm = c.hausdorffMm;
    this->Hausdorff95Mm = c.hausdorff95Mm;
    output->ShallowCopy(copyA);
  } catch (const std::exception&) {
    output->Initialize();
    this->Error.keepCurrent(this);
  }
  return 1;
}
