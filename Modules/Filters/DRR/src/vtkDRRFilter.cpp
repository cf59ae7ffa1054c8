#include "cementsph/drr/vtkDRRFilter.h"

#include "cementsph/drr/AttenuationVolume.h"

#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkStreamingDemandDrivenPipeline.h>

#include <omp.h>

#include <algorithm>
#include <exception>

vtkStandardNewMacro(vtkDRRFilter);

vtkDRRFilter::vtkDRRFilter() {
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(1);
}

cementsph::drr::DRRGeometry vtkDRRFilter::GetGeometry() const {
  cementsph::drr::DRRGeometry g;
  g.sadMm = this->SourceAxisDistance;
  g.sidMm = this->SourceImageDistance;
  g.rows = this->DetectorRows;
  g.cols = this->DetectorColumns;
  g.heightMm = this->DetectorHeight;
  g.widthMm = this->DetectorWidth;
  g.isocenterMm = {this->Isocenter[0], this->Isocenter[1], this->Isocenter[2]};
  g.gantryAngleDeg = this->GantryAngle;
  g.parallel = this->ParallelBeam;
  return g;
}

void vtkDRRFilter::SetGeometry(const cementsph::drr::DRRGeometry& g) {
  this->SetSourceAxisDistance(g.sadMm);
  this->SetSourceImageDistance(g.sidMm);
  this->SetDetectorRows(g.rows);
  this->SetDetectorColumns(g.cols);
  this->SetDetectorHeight(g.heightMm);
  this->SetDetectorWidth(g.widthMm);
  this->SetIsocenter(g.isocenterMm[0], g.isocenterMm[1], g.isocenterMm[2]);
  this->SetGantryAngle(g.gantryAngleDeg);
  this->SetParallelBeam(g.parallel);
}

int vtkDRRFilter::RequestInformation(vtkInformation*, vtkInformationVector**,
                                     vtkInformationVector* outputVector) {
  const cementsph::drr::DRRGeometry g = this->GetGeometry();
  const std::string problem = g.validate();
  if (!problem.empty()) {
    vtkErrorMacro(<< problem);
    return 0;
  }
  // The output grid is the detector, unrelated to the input's grid, so nothing is copied from it.
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  const int extent[6] = {0, g.cols - 1, 0, g.rows - 1, 0, 0};
  const double spacing[3] = {g.pixelWidthMm(), g.pixelHeightMm(), 1.0};
  const double origin[3] = {-0.5 * (g.cols - 1) * spacing[0], -0.5 * (g.rows - 1) * spacing[1], 0.0};
  const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  outInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), extent, 6);
  outInfo->Set(vtkDataObject::SPACING(), spacing, 3);
  outInfo->Set(vtkDataObject::ORIGIN(), origin, 3);
  outInfo->Set(vtkDataObject::DIRECTION(), identity, 9);
  vtkDataObject::SetPointDataActiveScalarInfo(outInfo, VTK_FLOAT, 1);
  return 1;
}

int vtkDRRFilter::RequestUpdateExtent(vtkInformation*, vtkInformationVector** inputVector,
                                      vtkInformationVector*) {
  // Any voxel can lie on some ray, so the whole input is always needed.
  vtkInformation* inInfo = inputVector[0]->GetInformationObject(0);
  inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT(),
              inInfo->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()), 6);
  return 1;
}

int vtkDRRFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                              vtkInformationVector* outputVector) {
  vtkImageData* input = vtkImageData::GetData(inputVector[0]);
  vtkImageData* output = vtkImageData::GetData(outputVector);
  const cementsph::drr::DRRGeometry g = this->GetGeometry();
  const std::string problem = g.validate();
  if (!input || !output || !problem.empty()) {
    vtkErrorMacro(<< (problem.empty() ? "missing input or output image" : problem));
    return 0;
  }

  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  output->SetExtent(outInfo->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()));
  output->SetSpacing(outInfo->Get(vtkDataObject::SPACING()));
  output->SetOrigin(outInfo->Get(vtkDataObject::ORIGIN()));
  output->AllocateScalars(VTK_FLOAT, 1);
  output->GetPointData()->GetScalars()->SetName("DRR");
  float* pixels = static_cast<float*>(output->GetScalarPointer());
  std::fill(pixels, pixels + static_cast<std::size_t>(g.rows) * g.cols, 0.0f);

  const int threads = this->NumberOfThreads > 0 ? this->NumberOfThreads : omp_get_max_threads();
  this->UpdateProgress(0.0);
  try {
    const cementsph::drr::AttenuationVolume volume(input, threads);
    this->UpdateProgress(0.05);
    const cementsph::drr::DetectorFrame frame = g.frame();
    if (volume.attenuatingVoxels() > 0) {
      int rowsDone = 0;
      // Rows in small dynamic chunks: rays through the middle of the object cost more than rays
      // that graze it, so a static split would leave one thread idle.
#pragma omp parallel for schedule(dynamic, 2) num_threads(threads)
      for (int j = 0; j < g.rows; ++j) {
        float* row = pixels + static_cast<std::size_t>(j) * g.cols;
        for (int i = 0; i < g.cols; ++i)
          row[i] = static_cast<float>(kPixelScale * volume.lineIntegral(frame.ray(i, j)));
        // Progress observers may touch non-thread-safe state, so only the calling thread reports.
        int done;
#pragma omp atomic capture
        done = ++rowsDone;
        if (omp_get_thread_num() == 0 && (done % 16 == 0))
          this->UpdateProgress(0.05 + 0.95 * done / g.rows);
      }
    }
  } catch (const std::exception& e) {
    // No half-made image downstream: a failed DRR leaves an empty output.
    output->Initialize();
    vtkErrorMacro(<< e.what());
    return 0;
  }
  this->UpdateProgress(1.0);
  return 1;
}

void vtkDRRFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SourceAxisDistance: " << this->SourceAxisDistance << " mm\n"
     << indent << "SourceImageDistance: " << this->SourceImageDistance << " mm\n"
     << indent << "Detector: " << this->DetectorRows << " x " << this->DetectorColumns << " pixels, "
     << this->DetectorHeight << " x " << this->DetectorWidth << " mm\n"
     << indent << "Isocenter: (" << this->Isocenter[0] << ", " << this->Isocenter[1] << ", "
     << this->Isocenter[2] << ") mm\n"
     << indent << "GantryAngle: " << this->GantryAngle << " deg\n"
     << indent << "ParallelBeam: " << this->ParallelBeam << "\n"
     << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
}
