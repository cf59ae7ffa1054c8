// "Model only what a scene needs": the scene's dimensionless numbers, computed before a run, and the
// pressure model they select (docs/architecture.md, "Choosing a model").
//
// Scales: outlet radius r0 = D/2, outlet speed v0 = Q / (2 pi r0^2) (a hemisphere of cement at the outlet),
// particle spacing d, cement density rho0 and initial viscosity mu, the medium's permeability k (pores
// resolved: the drag model's calibration, k / d^2 = 0.0711, Kozeny-Carman at porosity 0.8 - VALIDATION.md)
// and porosity phi.
//   Reynolds      Re = rho0 v0 d / mu                          inertia against viscosity at pore scale
//   Stokes        St = rho0 k v0 / (mu phi d)                  a particle's momentum relaxation time
//                                                             (phi rho0 k / mu... 1 / gamma) against d / v0
//   compression   C  = dp / (rho0 cs^2), dp = mu Q / (2 pi k r0)   what the equation of state (Eq. 6) would
//                                                             compress the cement by at the Darcy pressure
//   capillary     N  = p_cap / dp_pore, p_cap = 2 sigma / r_pore (sigma 0.025 N/m assumed for cement against
//                  marrow, r_pore = d/2), dp_pore = mu phi v_f d / k the viscous drop across one pore at the
//                  final front (hemisphere of the injected volume)
//   viscosity ratio M = mu / mu_marrow (marrow 0.1 Pa.s; 0.044-0.142 Pa.s, Zhong & Akkus 2011)
// Rule: the paper preset keeps its model. Otherwise, if Re and St are both below 0.1 the flow is creeping,
// and if C exceeds 0.01 the equation of state would compress the cement by more than 1 %: the incompressible
// Darcy filling on the voxel grid runs (voxel-darcy; it meets the oracles, VALIDATION.md; the particles'
// Poisson equation, "incompressible", does not yet and runs only when asked for). If C <= 0.01 the paper's
// equation of state is accurate and is kept. If Re or St >= 0.1
// inertia matters, which the overdamped models neglect: equation of state (use the paper preset's
// central-difference integrator). M >> 1 and N << 1 justify a single-phase model without capillarity; the
// reason says when they do not hold.
//
// Particles or voxels (issue 19 item 3). Both Darcy engines solve the same creeping flow; what only the
// particles give is a cement that is its own material points in resolved pore space: a free front that is
// not a fill fraction of a voxel, carried by particles finer than the pores. Creeping flow with C > 0.01
// therefore runs particle-darcy where
//   (a) the medium is pore-resolved (bone_model pore-resolved: the CT's pores are the cement's space, not a
//       continuum of HU-derived permeability; clinical CT, bone as a continuum, stays voxel-darcy),
//   (b) the CT resolves the pores: the mean pore chord L (the mean length of the pore runs along the three
//       axes in the region, the stereological mean intercept of the pore phase) is at least
//       kResolvedPoreVoxels voxels, and
//   (c) the particles resolve the pores: L >= kParticlesAcrossPore d. Why 8: on the bundled foam phantom (the
//       region about the tip: L = 3.26 mm, 6.9 voxels) particle-darcy agreed with voxel-darcy at d = 0.57 mm
//       (L / d = 5.7; 1 ml: Dice 0.88, spreading +0.24 mm, tip 1.13x) and not at d = 1.14 mm (L / d = 2.9;
//       5 ml: Dice 0.81, spreading +0.71 mm), 2026-12-03; 8 keeps a margin over the one resolution measured to
//       agree (its 5 ml case is unmeasured). The preset's d = 1.14 mm thus keeps the phantom and the test
//       scaffold (L = 7.2 mm, 6.3 spacings) on voxel-darcy.
// Open space (no solid in the region) is the limit L -> the region's size: a free front in open space.
// Otherwise voxel-darcy, the cheaper engine (BENCHMARKS.md), which meets the same oracles.
#pragma once

#include "cementsph/scene/SceneConfig.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cementsph::scene {

struct DimensionlessNumbers {
  double reynolds = 0, stokes = 0, compression = 0, capillaryOverViscous = 0, viscosityRatio = 0;
  double outletSpeedMPerS = 0, darcyPressurePa = 0, permeabilityM2 = 0, porosity = 1;
  double capillaryPressurePa = 0, frontPorePressurePa = 0;
  double meanPoreChordM = 0, particlesAcrossPore = 0; // (b), (c) above; 0 where not known
};

// The medium's pore scale (the rule above); poreResolved false (the default) leaves particles out.
struct PoreScale {
  bool poreResolved = false;
  double meanPoreChordM = 0;  // L
  double voxelSizeM = 0;      // the largest spacing
};

// L of a region's solid flags (index i + nx (j + ny k)), spacing per axis [m]: the pore voxels' total length
// along each axis over the number of pore runs along it, the three axes' lengths and runs summed. A region
// with no pore voxel has L = 0; one with no solid has L = its extent.
PoreScale poreScaleOf(const std::vector<std::uint8_t>& solid, const std::array<int, 3>& size,
                      const std::array<double, 3>& spacingM, bool poreResolved);

constexpr double kResolvedPoreVoxels = 3.0;
constexpr double kParticlesAcrossPore = 8.0;

struct ModelChoice {
  std::string pressureModel; // "voxel-darcy", "particle-darcy", "incompressible" or "equation-of-state"
  std::string model;         // what metrics.json calls it: "incompressible-darcy-on-voxels",
                             // "incompressible-darcy-on-particles" or "weakly-compressible"
  std::string reason;        // one sentence
  std::string recommended;   // the pressure model the numbers call for
  DimensionlessNumbers numbers;
  nlohmann::json numbersJson() const;
};

constexpr double kMarrowViscosityPaS = 0.1;
constexpr double kCementMarrowTensionNPerM = 0.025;
constexpr double kCalibratedPermeabilityOverD2 = 0.0711;

// `restDensity` [kg/m^3] and `soundSpeed` [m/s] the model's rho0 and cs; `porosity` of the medium at the tip.
// `pores` the medium's pore scale (poreScaleOf); the default (not pore-resolved) never selects particles.
ModelChoice chooseModel(const SceneConfig& scene, double restDensityKgPerM3, double soundSpeedMPerS, double porosity,
                        const PoreScale& pores = {});

} // namespace cementsph::scene
