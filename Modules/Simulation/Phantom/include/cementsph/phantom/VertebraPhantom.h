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
//
// The anatomy variant (issue 20, item 7; every option off by default, so the default phantom is unchanged voxel
// for voxel): marrow fat below the bone band inside the body (a sphere, fully enclosed by trabecular bone), disc
// spaces above and below the body (disc_hu between the body's end plates and those of neighbouring vertebral
// bodies, which continue to the field's edge; no posterior elements), and a basivertebral vein (a tube of
// blood HU from inside the body out through its posterolateral wall into the soft tissue). The known geometry
// is in VertebraResult (and its toJson), the oracle of the anatomy tests.
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
  // The anatomy variant (0 = off). Fat: a sphere centred 7 mm left, 3 mm anterior, 2 mm superior of the body's
  // centre (radius up to 6 mm keeps it 3 mm inside the trabecular bone). Discs: height of each disc space.
  // Vein: a tube of this radius along the segment veinStartMm -> veinEndMm of the result.
  double marrowFatRadiusMm = 0.0, marrowFatHu = -30.0;
  double discHeightMm = 0.0, discHu = 80.0;
  double veinRadiusMm = 0.0, veinHu = 60.0;
  void validate() const; // std::invalid_argument naming the option
};

struct VertebraResult {
  imaging::ImageType::Pointer ct;
  std::array<double, 3> bodyCentreMm{}, canalCentreMm{}, foramenMm{};
  std::array<double, 3> suggestedTipMm{}, suggestedDirection{}; // a transpedicular plan: tip in the body
  // The body: an elliptic cylinder about bodyCentreMm with these semi-axes (x, y) and half height (z).
  std::array<double, 3> bodySemiAxesMm{};
  // The variant's geometry (radius / height 0 where the option is off). Discs: the body's elliptic section,
  // z in [lower[0], lower[1]] and [upper[0], upper[1]].
  std::array<double, 3> marrowFatCentreMm{};
  double marrowFatRadiusMm = 0.0;
  std::array<double, 2> lowerDiscZMm{}, upperDiscZMm{};
  double discHeightMm = 0.0;
  std::array<double, 3> veinStartMm{}, veinEndMm{};
  double veinRadiusMm = 0.0;
  nlohmann::json toJson() const; // the variant's keys only where the variant is on
};

VertebraResult makeVertebra(const VertebraOptions& options);

} // namespace cementsph::phantom
