// The DRR filter: a 20 x 20 x 20 block of 1 mm voxels at 0 HU (water: mu = 0.022 /mm, plastimatch's
// convention) seen by a parallel beam along x. The central ray crosses the block's voxel boxes over 20 mm,
// so its pixel is 0.1 (plastimatch's per-cm scaling) * 0.022 /mm * 20 mm = 0.044; the side pixels, 30 mm off
// the axis, miss the block and read 0.
#include "Checks.h"

#include "cementsph/drr/vtkDRRFilter.h"

#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>

int checkDrr() {
  vtkNew<vtkImageData> block;
  block->SetDimensions(20, 20, 20);
  block->SetSpacing(1.0, 1.0, 1.0);
  block->SetOrigin(0.0, 0.0, 0.0);
  block->AllocateScalars(VTK_FLOAT, 1);
  auto* hu = static_cast<float*>(block->GetScalarPointer());
  for (vtkIdType i = 0; i < block->GetNumberOfPoints(); ++i) hu[i] = 0.0f;

  vtkNew<vtkDRRFilter> drr;
  drr->SetInputData(block);
  drr->ParallelBeamOn();
  drr->SetGantryAngle(0.0); // source on +x: rays run along -x; detector columns along +y
  drr->SetIsocenter(9.5, 9.5, 9.5);
  drr->SetDetectorColumns(3);
  drr->SetDetectorWidth(90.0); // 30 mm pixels: column centres at y = -20.5, 9.5, 39.5 mm
  drr->SetDetectorRows(1);
  drr->SetDetectorHeight(1.0);
  drr->Update();
  vtkImageData* image = drr->GetOutput();
  int failures = 0;
  const double lineIntegral = 0.1 * 0.022 * 20.0;
  failures += compare("DRR of a 20 mm water block, centre pixel", image->GetScalarComponentAsDouble(1, 0, 0, 0), lineIntegral, 1e-6);
  failures += compare("DRR, pixel beside the block", image->GetScalarComponentAsDouble(0, 0, 0, 0), 0.0, 1e-12);
  failures += compare("DRR, pixel beside the block (other side)", image->GetScalarComponentAsDouble(2, 0, 0, 0), 0.0, 1e-12);
  return failures;
}
