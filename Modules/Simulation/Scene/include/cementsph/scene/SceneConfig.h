// An injection scene: where the cannula is, what is injected, and how the CT becomes a porous solid.
// Read from JSON in which every key names its unit (Basafa et al. 2013, "Simulations" under "Foam Block
// Tests"). Keys (all optional except tip_mm):
//   scene_preset "paper"            baseline values below (the only scene preset)
//   preset "default"|"paper"        the model preset (cementsph::sph::modelPreset)
//   particle_radius_mm              r; spacing d = 2r, volume d^3 (VALIDATION.md)          paper 0.57
//   tip_mm [x,y,z]                  cannula tip in the CT's physical frame                  required
//   direction [x,y,z]               flow direction (normalised; not zero)                   [0,0,1]
//                                   from the entry point toward the tip; required where the tip is in a
//                                   vertebra (a patient CT: voxel-darcy's anatomy finds one, or labels_path)
//   cannula_inner_diameter_mm       11G regular wall                                        paper 2.388
//   cannula_length_mm               wall length behind the tip                              paper 90
//   cannula_wall (bool)             fixed-particle cannula wall                             true
//   flow_rate_ml_per_s                                                                      paper 0.05
//   volume_ml                                                                               paper 5
//   viscosity_pa_s                  constant, or the initial value of a linear rise         paper 100
//   viscosity_rate_pa_per_s         linear rise mu(t) = viscosity_pa_s + rate t (rate > 0)
//   viscosity_table [[t_s,mu_pa_s]] piecewise linear (not together with the two above)
//   threshold_hu                    solid where HU > threshold                              paper 0
//   roi_size_mm                     edge of the cube about the tip that is modelled         paper 40
//   snapshot_interval_s                                                                     1
//   snapshot_arrays "growth"|"flow" voxel-darcy: what the snapshots before the last hold: "growth" the voxels
//                                   holding cement then with their arrival times (particles_NNNN.pvtp of
//                                   pieces, a voxel written at most log4(snapshots) + 1 times); "flow" every
//                                   such voxel's volume, pressure and Darcy velocity then (a .vtp each, every
//                                   voxel every snapshot; docs/scene-figures.md)                  growth
//   simulated_ct_snapshots (bool)   also write simulated_ct_NNNN.nrrd at every particle snapshot false
//                                   (same numbering as particles_NNNN.vtp), simulated_ct_start.nrrd
//                                   at t = 0 (no cement: the background of X-ray sequences, paper
//                                   Fig. 12) and sequence.json listing them with their times
//   solid_mass_factor               fixed particle mass = factor rho0 V_voxel (> 0)          8
//                                   (ours, not the paper's: at factor 1 the compressed cloud, ~1.4 kPa against
//                                   rho0 cs^2 = 1.18 kPa, entered the solid; docs/scene-figures.md)
//   drag_coefficient, sound_speed_m_per_s, integrator   override the model preset
//   fixed_particle_sums "exact"|"tabulated"   how the solid's share of Eq. 2 / Eq. 5 is summed
//                                   (FixedParticleField.h)                    preset default: tabulated,
//                                                                             preset paper: exact
//   fixed_field_spacing_over_h      tabulated: grid spacing / h (0..1]                      0.25
//   max_displacement_over_h         overdamped: largest move per step / h (0..1]           0.25
//   neighbour_skin_over_h           Verlet skin / h (0..2]                                 model preset
//   pressure_model "auto"|"voxel-darcy"|"incompressible"|"equation-of-state"   the pressure model: voxel-darcy
//                                   the incompressible Darcy filling on the CT's voxels (VoxelDarcyFilling.h),
//                                   incompressible the particles' Poisson equation (IncompressibleDarcy.h),
//                                   equation-of-state the paper's Eq. 6; auto chooses from the scene's
//                                   dimensionless numbers (ModelSelection.h)                 auto
//   pore_permeability_m2            voxel-darcy: permeability of a resolved pore voxel   preset drag k0 = h^5/(Cf d^3)
//   viscosity_law "newtonian"|"power-law"|"carreau"   voxel-darcy: the cement's law (sph/Viscosity/)   newtonian
//   consistency_pa_s_n, flow_index  power law mu = K gamma_dot^(n-1) (and n for Carreau)        100, 1
//   zero_shear_viscosity_pa_s, infinite_shear_viscosity_pa_s, carreau_time_constant_s   Carreau   100, 0, 1
//   viscosity_min_pa_s, viscosity_max_pa_s   bounds of the apparent viscosity                1e-3, 1e6
//   mixing_to_injection_s           time from mixing to the start of injection                 0
//   curing_table [[t_s, factor]]    viscosity factor over time since mixing (piecewise linear; held outside
//                                   the table), multiplying any law                            none (1)
//   cement "<name>"                 a bundled cement's curing (sph/Viscosity/Curing.h: cmw1-25c, palacos-r-25c,
//                                   cemex-isoplastic-25c and their -37c; Nicholas et al. 2007): sets the
//                                   exponential curve's curing_time_s and cured_viscosity_pa_s (keys given
//                                   explicitly win)                                             none
//   curing_model "none"|"table"|"exponential"   the curing curve (Curing.h); exponential: mu(t) = mu_ref
//                                   exp((t - t_ref)/tau) through the law's viscosity (viscosity_pa_s, K or
//                                   mu0) at curing_reference_time_s and cured_viscosity_pa_s at curing_time_s
//                                   (both since mixing), held after it       exponential with cement, table
//                                                                            with curing_table, else none
//   curing_time_s, cured_viscosity_pa_s, curing_reference_time_s   the exponential's points   -, -, 0
//   cannula_gauge "11G"|"11G-thin"|...  sets cannula_inner_diameter_mm from the gauge table (TubeFlow.h: 8G,
//                                   10G, 10G-thin (or 10GTW), 10G-extra-thin (10GXTW), 11G, 12G, 13G; nominal)
//   bone_model "auto"|"pore-resolved"|"continuum"   pore-resolved: the paper's solid voxels; continuum: each
//                                   voxel's porosity and permeability from its HU (BoneCalibration.h); auto:
//                                   continuum when the tip's voxel is above threshold_hu (no pore resolved
//                                   there), pore-resolved otherwise                              auto
//   marrow_hu, bone_tissue_hu, kozeny_carman_diameter_mm, cortical_hu, soft_tissue_max_hu,
//   soft_tissue_permeability_m2     the continuum's calibration              0, 1400, 0.3, 350, 40, 1e-7
//   stop_at_first_leak (bool)       continuum: stop the injection when cement first leaves the target
//                                   vertebra (Modules/Simulation/Anatomy)                        false
//   allow_tip_outside_bone (bool)   continuum: run although the tip is in disc, canal, vessel, soft tissue
//                                   or air (a deliberate injection there); otherwise refused     false
//   labels_path                     continuum: a label map on the CT's grid (e.g. TotalSegmentator's output or
//                                   a 3D Slicer segmentation) for the tissue classes instead of the CT bone
//                                   rule (`inject --labels`)                                      none
//   label_table (object)            which labels are vertebrae, target_vertebra, bone, disc, canal, vessel,
//                                   air, soft_tissue (VertebraAnatomy.h)        TotalSegmentator's "total"
//   second_tip_withdrawal_mm, second_tip_volume_ml   voxel-darcy: a second tip on the same trajectory (the
//                                   two-depth technique): once volume_ml - second_tip_volume_ml is in, the
//                                   cannula is withdrawn this far along its axis (the tract it leaves opens to
//                                   the cement) and the last second_tip_volume_ml goes in there   none
//   capillary_tension_n_per_m       voxel-darcy: interfacial tension sigma of cement against the displaced
//                                   fluid; > 0 gives each pore voxel a capillary entry pressure
//                                   2 sigma cos(theta) / r (r: its distance to the solid on a pore-resolved CT,
//                                   the capillary-bundle throat sqrt(8 k / phi) on continuum bone;
//                                   VoxelDarcyInjectionModel.cpp, VALIDATION.md, the viscosity trend)     0 (off)
//   contact_angle_deg               voxel-darcy: the cement/marrow/bone contact angle theta, measured
//                                   through the marrow, [0, 90)                                0 (cos = 1)
// Errors (unknown key, null value, wrong type, out of range, missing tip) are std::invalid_argument with one
// line naming the key.
#pragma once

#include "cementsph/scene/BoneCalibration.h"
#include "cementsph/scene/SceneSettings.h"
#include "cementsph/sph/ModelParameters.h"
#include "cementsph/sph/Viscosity/Curing.h"
#include "cementsph/sph/Viscosity/Rheology.h"
#include "cementsph/sph/ViscositySchedule.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace cementsph::scene {

struct SceneConfig {
  std::string scenePreset = "paper";
  std::string modelPreset = "default";
  double particleRadiusMm = 0.57;
  std::optional<Eigen::Vector3d> tipMm;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  double cannulaInnerDiameterMm = 2.388;
  double cannulaLengthMm = 90.0;
  bool cannulaWall = true;
  double flowRateMlPerS = 0.05;
  double volumeMl = 5.0;
  double viscosityPaS = 100.0;
  std::optional<double> viscosityRatePaPerS;
  std::vector<std::pair<double, double>> viscosityTable; // (t [s], mu [Pa.s]); empty: constant or linear
  double thresholdHu = 0.0;
  double roiSizeMm = 40.0;
  double snapshotIntervalS = 1.0;
  std::string snapshotArrays = "growth"; // "growth" or "flow" (voxel-darcy)
  bool simulatedCtSnapshots = false;
  double solidMassFactor = 8.0;
  std::optional<double> dragCoefficient;
  std::optional<double> soundSpeedMPerS;
  std::optional<std::string> integrator;
  std::optional<std::string> fixedParticleSums;
  std::optional<double> fixedFieldSpacingOverH, maxDisplacementOverH, neighbourSkinOverH;
  std::string pressureModel = "auto";
  std::optional<double> porePermeabilityM2; // voxel-darcy: permeability of a resolved pore voxel [m^2]
  double capillaryTensionNPerM = 0.0;       // voxel-darcy: capillary entry 2 sigma cos(theta) / r at the front; 0 off
  double contactAngleDeg = 0.0;             // voxel-darcy: theta of the capillary entry, through the marrow [deg]
  // Rheology (voxel-darcy; sph::Rheology): the law, its parameters (the Newtonian law takes the viscosity
  // schedule above), bounds, and the curing factor over time since mixing.
  std::string viscosityLaw = "newtonian";
  sph::RheologyParameters rheology;
  double mixingToInjectionS = 0.0;
  std::vector<std::pair<double, double>> curingTable; // (time since mixing [s], viscosity factor); empty: 1
  std::optional<std::string> cement;                  // a bundled cement (sph::bundledCement)
  std::optional<std::string> curingModel;             // "none", "table", "exponential"; empty: inferred
  std::optional<double> curingTimeS, curedViscosityPaS; // the exponential's cured point (since mixing)
  double curingReferenceTimeS = 0.0;                  // since mixing, where the law's viscosity holds
  std::optional<std::string> cannulaGauge;
  // Bone (BoneCalibration.h): pore-resolved (the paper: HU > threshold_hu is solid) or a continuum from HU.
  std::string boneModel = "auto";
  BoneCalibration bone;
  bool stopAtFirstLeak = false;
  bool allowTipOutsideBone = false;
  std::string labelsPath;              // a label map on the CT's grid (NIfTI, NRRD, ...); empty: the CT bone rule
  nlohmann::json labelTable;           // which labels are which tissue (LabelTable::fromJson); null: TotalSegmentator
  std::optional<double> secondTipWithdrawalMm; // a second tip this far back along the axis; none: one tip
  double secondTipVolumeMl = 0.0;              // of volume_ml, injected at the second tip
  // The keys the user set: each key applySceneJson applied (the scene file's and the command line's overrides).
  // The driver warns of those the chosen engine does not read (InjectionModel.h, sceneKeysNotRead); a field
  // set in code is not a key the user set.
  std::set<std::string> explicitKeys;
  double curingFactor(double timeSinceInjectionStartS) const;
  bool hasSecondTip() const { return secondTipWithdrawalMm.has_value(); }
  // Whether the cannula's direction was given rather than defaulted: the key was set (scene file or override), or
  // code set a direction other than the default (a plan's trajectory). Code that means [0, 0, 1] on a patient CT
  // records "direction" in explicitKeys.
  bool directionGiven() const { return explicitKeys.count("direction") > 0 || direction != Eigen::Vector3d::UnitZ(); }
  Eigen::Vector3d secondTipMm() const { return *tipMm - *secondTipWithdrawalMm * direction.normalized(); }
  double secondTipStartS() const { return (volumeMl - secondTipVolumeMl) / flowRateMlPerS; }
  // The curing curve over time since mixing (throws std::invalid_argument as validate() for bad keys).
  sph::CuringCurve curing() const;
  // The law's viscosity the curing factor multiplies [Pa s]: viscosity_pa_s, consistency_pa_s_n (the power
  // law's viscosity at 1/s) or zero_shear_viscosity_pa_s.
  double referenceViscosityPaS() const;

  double spacingM() const { return 2.0 * particleRadiusMm * 1e-3; }
  double flowRateM3PerS() const { return flowRateMlPerS * 1e-6; }
  double volumeM3() const { return volumeMl * 1e-6; }
  double injectionDurationS() const { return volumeMl / flowRateMlPerS; }
  sph::ViscositySchedule viscositySchedule() const;
  sph::FixedSumMethod fixedSumMethod() const;
  // Throws std::invalid_argument naming the first key out of range (including a missing tip).
  void validate() const;
};

// Every key applySceneJson accepts (the list above), for the engines' declarations of the keys they read.
const std::set<std::string>& sceneKeyNames();

// The paper's scene: r 0.57 mm, 11G (ID 2.388 mm, 9 cm), 0.05 ml/s, 5 ml, 100 Pa.s, HU > 0, 40 mm cube.
SceneConfig scenePreset(const std::string& name);

// Applies the keys of `j` (an object) over `base`; unknown keys, null values and wrong types throw. Does
// not validate (call validate() once all overrides are in).
void applySceneJson(SceneConfig& base, const nlohmann::json& j);
// "key=value" with value in JSON (e.g. "volume_ml=0.2", "tip_mm=[1,2,3]", "integrator=\"overdamped\"";
// a bare word that is not JSON is taken as a string).
void applySceneOverride(SceneConfig& base, const std::string& assignment);

// Applies `settings` (SceneSettings.h) over `base`; a value the key refuses throws as applySceneJson does, naming the
// key. Does not validate.
void applySceneSettings(SceneConfig& base, const SceneSettings& settings);

// Reads a scene file: its scene_preset (default "paper") first, then its keys, then the command's settings.
// Validated. A refusal is one line blaming the command line's setting when it set the key at fault
// ("override tip_mm=[1,2,3] (command line): scene: key 'tip_mm' ..."), else the file ("PATH: scene: ...").
SceneConfig loadSceneFile(const std::string& path, const SceneSettings& settings);
SceneConfig loadSceneFile(const std::string& path, const std::vector<std::string>& overrides = {});
// The same from JSON text (validated).
SceneConfig sceneFromJson(const nlohmann::json& j, const SceneSettings& settings);
SceneConfig sceneFromJson(const nlohmann::json& j, const std::vector<std::string>& overrides = {});

nlohmann::json toJson(const SceneConfig& scene);

} // namespace cementsph::scene
