// Every numeric choice of the phantom's post-scan injection, pinned here, so that a change of an engine,
// preset or scene default does not silently change what `cementsph phantom` makes (Data/foam-phantom is
// regenerated and compared by Applications/cementsph/test/PhantomReproducibilityTest). The choices the scene can set are
// set on the scene (phantomInjectionScene); the model preset's values that no scene key reaches are checked
// against the preset before the run (checkModelPreset), and a mismatch stops the generator with one line.
//
// The model is the weakly compressible SPH of Basafa et al. 2013 with the Eq. 9 drag, overdamped, h = d,
// Cf = 8.7: the engine's preset "default" when this was written. The phantom is the "fine" run of the
// pipeline: exact pair sums over the fixed particles (no table) and at most 0.05 h per overdamped step
// (the inject default is the h/4 table and 0.25 h; VALIDATION.md measures what those cost).
#pragma once

#include "cementsph/scene/SceneConfig.h"

#include <nlohmann/json.hpp>

#include <array>
#include <string>

namespace cementsph::phantom {

struct PhantomNumerics {
  // The preset that means the weakly compressible drag model. If the engine's "default" becomes another model,
  // name here the preset that keeps this one (checkModelPreset refuses a preset that differs).
  std::string modelPreset = "default";
  // Preset values no scene key sets: checked, not set.
  double hOverD = 1.0;                // h = d
  double restDensityKgPerM3 = 1180.0; // rho0
  std::string viscosityModel = "drag"; // Eq. 9
  double overdampedStability = 1.5;   // dt <= C gamma h^2 / cs^2
  double neighbourSkinOverH = 0.2;    // Verlet skin (set on the scene too)
  bool relisting = true;              // neighbour-list relisting (the same pairs as full rebuilds)
  // Set on the scene.
  std::string integrator = "overdamped";
  // The incompressible Darcy filling on the voxels (VoxelDarcyFilling.h), the creeping-flow default since
  // issue 9; the particle settings below then only document what the particle model would use.
  std::string pressureModel = "voxel-darcy";
  double dragCoefficient = 8.7;
  double soundSpeedMPerS = 1.0;
  std::string fixedParticleSums = "exact"; // pair by pair (no table)
  double maxDisplacementOverH = 0.05;      // largest move per overdamped step / h
  double particleRadiusMm = 0.57;          // r; d = 2r
  double cannulaInnerDiameterMm = 2.388;   // 11G
  double cannulaLengthMm = 90.0;
  bool cannulaWall = true;
  double thresholdHu = 0.0;   // solid where HU > threshold
  double roiSizeMm = 40.0;
  double solidMassFactor = 8.0;
  // The simulated CT the cement is cut from: HU_pre + k rho / rho0.
  double huPerRelativeDensity = 3000.0;
};

// The scene of the phantom's injection: every key the scene has, from `numerics`, the tip, volume, viscosity
// and rate; direction +z; no snapshots. Validated.
scene::SceneConfig phantomInjectionScene(const PhantomNumerics& numerics, const std::array<double, 3>& tipMm,
                                         double volumeMl, double viscosityPaS, double flowRateMlPerS);

// Throws std::runtime_error (one line naming the value) when the model preset's values that no scene key
// sets differ from `numerics` (e.g. after the engine's default model changed).
void checkModelPreset(const PhantomNumerics& numerics);

// Every value above, each key naming its unit (truth.json's injection.numerics).
nlohmann::json toJson(const PhantomNumerics& numerics);

} // namespace cementsph::phantom
