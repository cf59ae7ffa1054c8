// vtkDRRFilter: a digitally reconstructed radiograph of a CT volume, as a VTK image algorithm.
// Input: vtkImageData of HU (any numeric scalar type; origin, spacing and VTK 9.1's direction matrix
// are all honoured). Output: a 2-D float vtkImageData (cols x rows x 1) of line integrals, with
// plastimatch's conventions (see DRRGeometry.h and AttenuationVolume.h):
//   pixel = sum over the voxels a ray crosses of mu (1/mm) * length (mm), divided by 10.
// The division by 10 is plastimatch's scaling (its output is the integral in "per cm" units of 10 mm);
// it is kept so that our images and `plastimatch drr` images can be compared pixel for pixel.
// Output geometry: spacing = detector pixel size (mm); origin puts the detector centre at (0, 0);
// row j = 0 is the bottom of the detector (VTK's convention), i runs along the detector's u axis.
// Everything is CPU arithmetic (no GL context), threaded with OpenMP over detector rows.
#pragma once

#include "cementsph/drr/DRRGeometry.h"

#include <vtkImageAlgorithm.h>

class vtkDRRFilter : public vtkImageAlgorithm {
public:
  static vtkDRRFilter* New();
  vtkTypeMacro(vtkDRRFilter, vtkImageAlgorithm)

  // pixel = kPixelScale * (line integral of mu in 1/mm over mm): plastimatch's division by 10.
  static constexpr double kPixelScale = 0.1;
  void PrintSelf(ostream& os, vtkIndent indent) override;

  // Source-axis and source-image distances, mm (plastimatch's defaults 1000 and 1500).
  vtkSetMacro(SourceAxisDistance, double);
  vtkGetMacro(SourceAxisDistance, double);
  vtkSetMacro(SourceImageDistance, double);
  vtkGetMacro(SourceImageDistance, double);

  // Detector resolution in pixels and physical size in mm.
  vtkSetMacro(DetectorRows, int);
  vtkGetMacro(DetectorRows, int);
  vtkSetMacro(DetectorColumns, int);
  vtkGetMacro(DetectorColumns, int);
  vtkSetMacro(DetectorHeight, double);
  vtkGetMacro(DetectorHeight, double);
  vtkSetMacro(DetectorWidth, double);
  vtkGetMacro(DetectorWidth, double);

  // Isocentre in the volume's physical (patient) coordinates, mm.
  vtkSetVector3Macro(Isocenter, double);
  vtkGetVector3Macro(Isocenter, double);

  // Gantry angle about z, degrees: 0 puts the source on +x of the isocentre, 90 on -y (plastimatch's sense).
  vtkSetMacro(GantryAngle, double);
  vtkGetMacro(GantryAngle, double);

  // Parallel rays along the beam axis instead of a cone from the source (distances are then unused).
  vtkSetMacro(ParallelBeam, bool);
  vtkGetMacro(ParallelBeam, bool);
  vtkBooleanMacro(ParallelBeam, bool);

  // OpenMP threads; 0 (default) uses OpenMP's default (OMP_NUM_THREADS or the number of cores).
  vtkSetClampMacro(NumberOfThreads, int, 0, 4096);
  vtkGetMacro(NumberOfThreads, int);

  // The geometry the parameters describe (the filter's single source of truth for rays).
  cementsph::drr::DRRGeometry GetGeometry() const;
  // Sets every geometry parameter at once (Modified() only if one changes).
  void SetGeometry(const cementsph::drr::DRRGeometry& geometry);

protected:
  vtkDRRFilter();
  ~vtkDRRFilter() override = default;

  int RequestInformation(vtkInformation* request, vtkInformationVector** inputVector,
                         vtkInformationVector* outputVector) override;
  int RequestUpdateExtent(vtkInformation* request, vtkInformationVector** inputVector,
                          vtkInformationVector* outputVector) override;
  int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                  vtkInformationVector* outputVector) override;

  double SourceAxisDistance = 1000.0;
  double SourceImageDistance = 1500.0;
  int DetectorRows = 512;
  int DetectorColumns = 512;
  double DetectorHeight = 400.0;
  double DetectorWidth = 400.0;
  double Isocenter[3] = {0.0, 0.0, 0.0};
  double GantryAngle = 0.0;
  bool ParallelBeam = false;
  int NumberOfThreads = 0;

private:
  vtkDRRFilter(const vtkDRRFilter&) = delete;
  void operator=(const vtkDRRFilter&) = delete;
};
