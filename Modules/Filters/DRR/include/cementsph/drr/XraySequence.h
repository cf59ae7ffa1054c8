// An X-ray (fluoroscopy) sequence of a cement injection, as the paper's Fig. 12 (Basafa et al. 2013) set
// simulated frames beside the C-arm's: one DRR per frame volume, all with one geometry (vtkDRRFilter), and
// the cement in each frame segmented against the first frame.
//
// Segmentation rule: cement where DRR_k - DRR_0 > threshold, DRR_0 the first frame (taken before the
// injection: `inject` writes simulated_ct_start.nrrd for this). The threshold is given as a thickness of
// water, cementThresholdWaterMm, because DRR pixels are line integrals (plastimatch's: sum mu l / 10): the
// threshold in DRR units is 0.022 /mm x cementThresholdWaterMm x 0.1. The default, 1 mm of water, is the
// attenuation that 0.33 mm of cement 3000 HU above its surroundings adds (the simulated CT's k), so the
// mask's edge lies where the cement along the ray is about 1/3 mm thick, and CT noise (20 HU, ~0.1 mm of
// water-equivalent along a 40 mm ray) stays well below it.
//
// Component rule (optional, as `compare` keeps the 3-D component at the injection point): given the
// injection point, each mask keeps only its 8-connected region at the point's projection, or, when no
// region contains it, the region nearest to it within injectionSearchRadiusMm (measured in the isocentre
// plane); no region there gives an empty mask. A connected cement body projects to one connected region,
// so this drops only what is not connected to the injection: subtraction artefacts such as the streaks a
// sub-voxel misregistration leaves along faces parallel to the beam. Without the point every pixel above
// the threshold counts.
//
// Projected area: the mask's pixel count times the pixel area, at the detector (detectorAreaMm2), and
// scaled to the plane through the isocentre by (sad / sid)^2 (projectedAreaMm2, the size at the patient;
// a parallel beam has no magnification). A sphere of radius r at the isocentre gives projectedAreaMm2 =
// pi r^2 sad^2 / (sad^2 - r^2), i.e. pi r^2 to 3e-5 for r = 5 mm at sad 1000 mm.
#pragma once

#include "cementsph/drr/DRRGeometry.h"

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include <cstddef>
#include <optional>
#include <vector>

namespace cementsph::drr {

struct XraySequenceOptions {
  DRRGeometry geometry;
  double cementThresholdWaterMm = 1.0; // mm of water (see above); > 0
  std::optional<Vec3> injectionPointMm; // the component rule above; none: every pixel above the threshold
  double injectionSearchRadiusMm = 10.0; // in the isocentre plane
  int threads = 0;                     // OpenMP threads for the DRRs (0: OpenMP's default)
};

struct XrayFrame {
  double timeS = 0.0;
  vtkSmartPointer<vtkImageData> drr;        // vtkDRRFilter's output: float, cols x rows x 1, spacing in mm
  vtkSmartPointer<vtkImageData> cementMask; // unsigned char 0/1 on the DRR's grid (empty for frame 0)
  std::size_t cementPixels = 0;
  std::size_t regionsAboveThreshold = 0; // 8-connected regions before the component rule
  double detectorAreaMm2 = 0.0;  // cementPixels x pixel area at the detector
  double projectedAreaMm2 = 0.0; // detectorAreaMm2 x (sad / sid)^2: the area at the isocentre plane
};

class XraySequence {
public:
  // Throws std::invalid_argument for a geometry DRRGeometry::validate() refuses or a threshold that is not
  // a positive finite number of mm.
  explicit XraySequence(const XraySequenceOptions& options);

  // Projects volumeHU (vtkImageData of HU, any geometry vtkDRRFilter accepts) and segments it against the
  // first frame. Times must increase strictly. Throws std::invalid_argument for a null volume, a volume
  // without scalars, or a time that is not finite or not after the previous frame's; std::runtime_error if
  // the DRR fails (the message is vtkDRRFilter's). The sequence is unchanged when it throws.
  void addFrame(double timeS, vtkImageData* volumeHU);

  const std::vector<XrayFrame>& frames() const { return frames_; }
  const XraySequenceOptions& options() const { return options_; }

  // The threshold in DRR units: AttenuationVolume::kMuWaterPerMm x cementThresholdWaterMm x vtkDRRFilter::kPixelScale.
  double thresholdDrr() const;
  // DRR units per mm of water (0.0022).
  static double drrPerWaterMm();

private:
  XraySequenceOptions options_;
  std::vector<XrayFrame> frames_;
};

} // namespace cementsph::drr
