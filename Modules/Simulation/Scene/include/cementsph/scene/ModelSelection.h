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
#pragma once

#include "cementsph/scene/SceneConfig.h"

#include <nlohmann/json.hpp>

#include <string>

namespace cementsph::scene {

struct DimensionlessNumbers {
  double reynolds = 0, stokes = 0, compression = 0, capillaryOverViscous = 0, viscosityRatio = 0;
  double outletSpeedMPerS = 0, darcyPressurePa = 0, permeabilityM2 = 0, porosity = 1;
  double capillaryPressurePa = 0, frontPorePressurePa = 0;
};

struct ModelChoice {
  std::string pressureModel; // "voxel-darcy", "incompressible" or "equation-of-state"
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
ModelChoice chooseModel(const SceneConfig& scene, double restDensityKgPerM3, double soundSpeedMPerS, double porosity);

} // namespace cementsph::scene
