// Bone as a continuum where the CT does not resolve the pores (issue "Patient CTs at clinical resolution"):
// per voxel, HU -> bone volume fraction -> porosity -> permeability, and which voxels are cortex (closed)
// or soft tissue (where leaked cement goes).
//
// Decisions and sources (VALIDATION.md, "Bone as a continuum"):
//  * BV/TV from HU by linear mixing of marrow and bone tissue within a voxel (partial volume: the CT number
//    of a mixture is the volume-weighted mean of its parts): BV/TV = (HU - HU_marrow) / (HU_tissue - HU_marrow),
//    clamped to [0, 1]. HU_marrow 0 (water-equivalent marrow), HU_tissue 1400 (a compact-bone ROI at clinical
//    resolution, clinical-notes). Vertebral trabecular bone at 80-200 HU (Pickhardt 2013) then has BV/TV
//    0.06-0.14, the range of osteoporotic to normal vertebrae. Scene keys marrow_hu, bone_tissue_hu (a
//    calibration phantom's values, where the scanner has one).
//  * Porosity phi = 1 - BV/TV.
//  * Permeability by Kozeny-Carman, k = d^2 phi^3 / (180 (1 - phi)^2) (Carman 1937), d the trabecular
//    thickness scale, 0.3 mm by default (scene key kozeny_carman_diameter_mm): k = 3.6e-8 m^2 at phi = 0.90,
//    within the 3.4-4.5e-8 m^2 Baroud et al. 2004 measured in human vertebral cores.
//  * Cortex: HU above cortical_hu (350 HU by default: the thin vertebral cortex shows 300-1100 HU at 1-2 mm
//    voxels, trabecular bone 80-200 HU) is impermeable.
//  * Soft tissue: HU below soft_tissue_max_hu (40 HU: fat -100, muscle and spinal fluid 0-40) is outside bone:
//    cement there is leakage. It is modelled as an open medium (phi 1) of permeability
//    soft_tissue_permeability_m2 (1e-7 m^2, an assumption: a leak path offers little resistance).
#pragma once

namespace cementsph::scene {

struct BoneCalibration {
  double marrowHu = 0.0;
  double boneTissueHu = 1400.0;
  double kozenyCarmanDiameterMm = 0.3;
  double corticalHu = 350.0;
  double softTissueMaxHu = 40.0;
  double softTissuePermeabilityM2 = 1e-7;
  double minimumPorosity = 0.05; // bone denser than this (BV/TV > 0.95) below cortical_hu is kept open a little

  enum class Tissue { Cortex, Trabecular, SoftTissue };
  Tissue tissue(double hu) const {
    if (hu > corticalHu) return Tissue::Cortex;
    if (hu < softTissueMaxHu) return Tissue::SoftTissue;
    return Tissue::Trabecular;
  }
  double boneVolumeFraction(double hu) const {
    const double f = (hu - marrowHu) / (boneTissueHu - marrowHu);
    return f < 0 ? 0.0 : f > 1 ? 1.0 : f;
  }
  // Porosity of a voxel (0 for cortex, 1 for soft tissue).
  double porosity(double hu) const {
    switch (tissue(hu)) {
    case Tissue::Cortex: return 0.0;
    case Tissue::SoftTissue: return 1.0;
    case Tissue::Trabecular: break;
    }
    const double phi = 1.0 - boneVolumeFraction(hu);
    return phi < minimumPorosity ? minimumPorosity : phi;
  }
  // Permeability of a voxel [m^2] (meaningless where the porosity is 0).
  double permeability(double hu) const {
    if (tissue(hu) == Tissue::SoftTissue) return softTissuePermeabilityM2;
    const double phi = porosity(hu);
    if (phi <= 0) return 0.0;
    const double d = kozenyCarmanDiameterMm * 1e-3;
    const double open = phi < 0.999 ? phi : 0.999; // Kozeny-Carman diverges at phi = 1
    return d * d * open * open * open / (180.0 * (1.0 - open) * (1.0 - open));
  }
  // Empty when the values are consistent, else one line naming the scene key.
  const char* problem() const {
    if (!(boneTissueHu > marrowHu)) return "bone_tissue_hu must be above marrow_hu";
    if (!(kozenyCarmanDiameterMm > 0 && kozenyCarmanDiameterMm < 10)) return "kozeny_carman_diameter_mm must be in (0, 10) mm";
    if (!(corticalHu > softTissueMaxHu)) return "cortical_hu must be above soft_tissue_max_hu";
    if (!(softTissuePermeabilityM2 >= 1e-18 && softTissuePermeabilityM2 <= 1e-3))
      return "soft_tissue_permeability_m2 must be between 1e-18 and 1e-3 m^2";
    return nullptr;
  }
};

} // namespace cementsph::scene
