// The inject runner's path for the voxel-grid Darcy filling (pressure_model "voxel-darcy", the default for
// creeping flow; VoxelDarcyFilling.h): same files and metrics as the particle path (InjectionRunner.h), with
// the cement as filled voxels. particles_NNNN.vtp then holds one point per voxel that holds cement (its
// centre, mm, the CT's frame) with fill_fraction, cement_volume_mm3, pressure_pa, darcy_velocity_m_per_s,
// viscosity_pa_s, porosity, permeability_m2, arrival_time_s, age_s, and as the particle path's arrays
// velocity_m_per_s (the interstitial velocity q / phi) and density_kg_per_m3 (rho0: incompressible). Also
// cement_labels.nrrd: a label map on the simulated CT's grid (1 cement in bone, 2 leaked cement), which
// `cementsph inject` draws as cement_slices.png (leaks in red) and 3D Slicer opens as a segmentation.
#pragma once

#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/scene/ModelSelection.h"
#include "cementsph/scene/PorousSolid.h"
#include "cementsph/sph/Presets.h"

#include <chrono>
#include <string>

namespace cementsph::scene::detail {

struct VoxelDarcyRunInputs {
  const sph::ModelPreset& preset;
  const sph::ModelParameters& model; // h, Cf, rho0 of the preset with the scene's overrides
  const PorousSolid& solid;
  const ModelChoice& choice;
  std::chrono::steady_clock::time_point wallStart;
  bool continuum = false;     // bone as a continuum from HU (BoneCalibration.h); else pore-resolved
  std::string boneModelReason;
  bool resampled = false;     // the CT was oblique and is the axis-aligned resampling (AxisAlignedCT.h)
};

InjectionRunResult runVoxelDarcyInjection(const imaging::ImageType* ct, const SceneConfig& scene,
                                          const InjectionRunOptions& options, const VoxelDarcyRunInputs& inputs);

} // namespace cementsph::scene::detail
