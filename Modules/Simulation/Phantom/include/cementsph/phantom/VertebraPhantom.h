// A clinical-resolution vertebra phantom (issue "Patient CTs at clinical resolution", item 5): a CT like a
// patient's at about 1 mm voxels, in which the trabeculae are not resolved, for the continuum bone model
// (BoneCalibration.h), leakage and planning.
//
// Geometry in the patient frame (LPS, mm; origin at the first voxel centre, identity direction): a vertebral
// body, an elliptic cylinder (semi-axes 20 mm left-right, 15 mm anterior-posterior, 25 mm high) whose cortex
// (1 mm, end plates included) is at cortical_hu; its trabecular bone's HU varies smoothly, lowest at the
// centre (trabecular_centre_hu) and highest at the rim (trabecular_rim_hu), an osteoporotic pattern; posterior
// elements (pedicles and a lamina, cortical bone) around a spinal canal (radius 8 mm, CSF at canal_hu) behind
// the body; a basivertebral foramen, a 3 mm opening in the body's posterior wall at mid height, the leak path
// into the canal; soft tissue (soft_tissue_hu) around. Partial volume: each voxel is the mean of 3^3 sub-samples.
// Gaussian noise (noise_hu, seeded), HU rounded.
#pragma once

#include "cementsph/imaging/ImageTypes.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>

namespace cementsph::phantom {

struct VertebraOptions {
  std::array<double, 3> spacingMm{1.0, 1.0, 1.5};
  std::array<double, 3> fieldMm{64, 70, 45};  // the CT's extent
  double corticalHu = 700.0, trabecularCentreHu = 90.0, trabecularRimHu = 170.0;
  double canalHu = 10.0, softTissueHu = 20.0;
  double foramenDiameterMm = 3.0;              // 0: an intact posterior wall
  double noiseHu = 10.0;
  std::uint64_t seed = 1;
  void validate() const; // std::invalid_argument naming the option
};

struct VertebraResult {
  imaging::ImageType::Pointer ct;
  std::array<double, 3> bodyCentreMm{}, canalCentreMm{}, foramenMm{};
  std::array<double, 3> suggestedTipMm{}, suggestedDirection{}; // a transpedicular plan: tip in the body
  nlohmann::json toJson() const;
};

VertebraResult makeVertebra(const VertebraOptions& options);

} // namespace cementsph::phantom
