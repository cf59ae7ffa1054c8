#include "cementsph/drr/ProjectVolume.h"

#include "cementsph/drr/vtkDRRFilter.h"

#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkNew.h>
#include <vtkPointData.h>

#include <stdexcept>
#include <string>

namespace cementsph::drr {

vtkSmartPointer<vtkImageData> projectVolume(vtkImageData* volumeHU, const DRRGeometry& geometry, int threads) {
  vtkNew<vtkDRRFilter> filter;
  filter->SetInputData(volumeHU);
  filter->SetGeometry(geometry);
  filter->SetNumberOfThreads(threads);
  // VTK errors become one exception message (an observer also keeps VTK from printing them).
  std::string error;
  vtkNew<vtkCallbackCommand> onError;
  onError->SetClientData(&error);
  onError->SetCallback([](vtkObject*, unsigned long, void* client, void* callData) {
    std::string text = callData ? static_cast<const char*>(callData) : "";
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    const auto colon = text.rfind("): "); // "...vtkDRRFilter (0x...): message"
    *static_cast<std::string*>(client) = colon == std::string::npos ? text : text.substr(colon + 3);
  });
  filter->AddObserver(vtkCommand::ErrorEvent, onError);
  filter->Update();
  if (!error.empty() || !filter->GetOutput()->GetPointData()->GetScalars())
    throw std::runtime_error("the DRR could not be computed" + (error.empty() ? "" : ": " + error));
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->ShallowCopy(filter->GetOutput());
  return image;
}

} // namespace cementsph::drr
