#include "cementsph/pipeline/vtkLabelIsosurfaceFilter.h"

#include "cementsph/surfacemetrics/Isosurface.h"

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <cstdint>

vtkStandardNewMacro(vtkLabelIsosurfaceFilter);

void vtkLabelIsosurfaceFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "InsideFrom: " << this->InsideFrom << "\n";
  os << indent << "SmoothingSigmaVoxels: " << this->SmoothingSigmaVoxels << "\n";
}

int vtkLabelIsosurfaceFilter::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  return 1;
}

int vtkLabelIsosurfaceFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                          vtkInformationVector* outputVector) {
  vtkImageData* input = vtkImageData::GetData(inputVector[0]);
  vtkPolyData* output = vtkPolyData::GetData(outputVector, 0);
  output->Initialize();
  vtkDataArray* values = input ? input->GetPointData()->GetScalars() : nullptr;
  if (!values) return 1; // nothing upstream (a failed filter reported it): no surface
  // The 0/1 mask the surface metrics take, on the input's geometry (direction included).
  auto mask = vtkSmartPointer<vtkImageData>::New();
  mask->CopyStructure(input);
  mask->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto* m = static_cast<std::uint8_t*>(mask->GetScalarPointer());
  for (vtkIdType i = 0; i < input->GetNumberOfPoints(); ++i) m[i] = values->GetComponent(i, 0) >= this->InsideFrom;
  cementsph::surfacemetrics::IsosurfaceOptions options;
  options.smoothingSigmaVoxels = this->SmoothingSigmaVoxels;
  output->ShallowCopy(cementsph::surfacemetrics::isosurface(mask, options));
  return 1;
}
