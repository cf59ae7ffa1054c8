// vtkCementSPHImageReader: a CT (or any scalar volume) as the source of a VTK pipeline, read by the project's
// own reader (cementsph/imaging/VolumeIO.h: NRRD, MetaImage, NIfTI, a DICOM series directory), so the output
// keeps the file's full geometry: origin and spacing in mm and the direction matrix, the CT's patient frame
// (LPS). Debian's VTK offers only the MPI NRRD reader (vtkPNrrdReader, which fails without an MPI
// controller) and VTK's readers drop the direction matrix, so a pipeline on a real CT starts here.
// Output: float vtkImageData (HU as stored; named "hu"), extent starting at 0.
// Errors (no file, unreadable, refused header): the output is empty, ErrorEvent fires with the one-line
// message (no VTK error print) and GetErrorMessage()/RethrowIfFailed() keep it; the next filter then reports
// its missing input.
#pragma once

#include "cementsph/pipeline/FilterError.h"

#include <vtkImageAlgorithm.h>
#include <vtkSmartPointer.h>

#include <string>

class vtkImageData;

class vtkCementSPHImageReader : public vtkImageAlgorithm {
public:
  static vtkCementSPHImageReader* New();
  vtkTypeMacro(vtkCementSPHImageReader, vtkImageAlgorithm)
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetFileName(const std::string& path);
  const std::string& GetFileName() const { return this->FileName; }

  const std::string& GetErrorMessage() const { return this->Error.message(); }
  void RethrowIfFailed() const { this->Error.rethrow(); }

protected:
  vtkCementSPHImageReader();
  ~vtkCementSPHImageReader() override = default;
  int RequestInformation(vtkInformation* request, vtkInformationVector** inputVector,
                         vtkInformationVector* outputVector) override;
  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                  vtkInformationVector* outputVector) override;

  std::string FileName;
  // The volume is read once per file name in RequestInformation (the geometry needs the header, and the
  // project's readers read header and voxels together) and handed out in RequestData.
  vtkSmartPointer<vtkImageData> Volume;
  vtkMTimeType VolumeTime = 0;
  cementsph::pipeline::FilterError Error;

private:
  vtkCementSPHImageReader(const vtkCementSPHImageReader&) = delete;
  void operator=(const vtkCementSPHImageReader&) = delete;
};
