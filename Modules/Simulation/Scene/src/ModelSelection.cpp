#include "cementsph/scene/ModelSelection.h"

#include <cmath>
#include <cstdio>

namespace cementsph::scene {

namespace {
constexpr double kPi = 3.14159265358979323846;
std::string g3(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", x);
  return b;
}
} // namespace

nlohmann::json ModelChoice::numbersJson() const {
  const DimensionlessNumbers& n = numbers;
  return {{"reynolds", n.reynolds},
          {"stokes", n.stokes},
          {"compression_darcy_over_rho0_cs2", n.compression},
          {"capillary_over_viscous_at_front", n.capillaryOverViscous},
          {"cement_over_marrow_viscosity", n.viscosityRatio},
          {"outlet_speed_m_per_s", n.outletSpeedMPerS},
          {"darcy_pressure_estimate_pa", n.darcyPressurePa},
          {"permeability_estimate_m2", n.permeabilityM2},
          {"porosity", n.porosity},
          {"capillary_pressure_estimate_pa", n.capillaryPressurePa},
          {"front_pore_pressure_drop_pa", n.frontPorePressurePa}};
}

ModelChoice chooseModel(const SceneConfig& scene, double rho0, double soundSpeed, double porosity) {
  ModelChoice c;
  DimensionlessNumbers& n = c.numbers;
  const double d = scene.spacingM(), mu = scene.viscositySchedule().at(0.0);
  const double Q = scene.flowRateM3PerS(), r0 = 0.5 * scene.cannulaInnerDiameterMm * 1e-3;
  const double phi = (porosity > 0 && porosity <= 1) ? porosity : 1.0;
  const double k = kCalibratedPermeabilityOverD2 * d * d;
  n.porosity = phi;
  n.permeabilityM2 = k;
  n.outletSpeedMPerS = Q / (2 * kPi * r0 * r0);
  n.darcyPressurePa = mu * Q / (2 * kPi * k * r0);
  n.reynolds = rho0 * n.outletSpeedMPerS * d / mu;
  n.stokes = rho0 * k * n.outletSpeedMPerS / (mu * phi * d);
  n.compression = n.darcyPressurePa / (rho0 * soundSpeed * soundSpeed);
  const double Rf = std::cbrt(3.0 * scene.volumeM3() / (2 * kPi * phi)); // final hemisphere
  const double vf = Q / (2 * kPi * Rf * Rf * phi);
  n.frontPorePressurePa = mu * phi * vf * d / k;
  n.capillaryPressurePa = 2.0 * kCementMarrowTensionNPerM / (0.5 * d);
  n.capillaryOverViscous = n.capillaryPressurePa / n.frontPorePressurePa;
  n.viscosityRatio = mu / kMarrowViscosityPaS;

  std::string caveats;
  if (n.viscosityRatio < 100) caveats += "; the marrow is only " + g3(n.viscosityRatio) + "x less viscous: a single-phase model overestimates the spreading";
  if (n.capillaryOverViscous > 0.1) caveats += "; capillary pressure is " + g3(n.capillaryOverViscous) + " of the viscous pressure at the front: capillarity is not modelled";
  const std::string numbers = "Re = " + g3(n.reynolds) + ", St = " + g3(n.stokes) + ", compression " + g3(n.compression);
  if (scene.pressureModel != "auto") {
    c.pressureModel = scene.pressureModel;
    c.reason = "forced by the scene key pressure_model (" + numbers + ")";
  } else if (scene.modelPreset == "paper") {
    c.pressureModel = "equation-of-state";
    c.reason = "the paper preset keeps the paper's weakly compressible model, Eq. 6 (" + numbers + ")";
  } else if (n.reynolds >= 0.1 || n.stokes >= 0.1) {
    c.pressureModel = "equation-of-state";
    c.reason = "inertia is not negligible (" + numbers + "): the creeping-flow models do not apply; use the paper preset's central-difference integrator";
  } else if (n.compression > 0.01) {
    c.pressureModel = "voxel-darcy";
    c.reason = "creeping flow (" + numbers + "): the equation of state would compress the cement at the Darcy pressure, so the cement is incompressible and its pressure is solved by Darcy's law on the CT's voxels (pressure in gauge Pa)";
  } else {
    c.pressureModel = "equation-of-state";
    c.reason = "creeping flow with compression below 1 % (" + numbers + "): the paper's weakly compressible model is accurate";
  }
  c.reason += caveats;
  if (c.recommended.empty()) c.recommended = c.pressureModel;
  c.model = c.pressureModel == "voxel-darcy"      ? "incompressible-darcy-on-voxels"
            : c.pressureModel == "incompressible" ? "incompressible-darcy-on-particles"
                                                  : "weakly-compressible";
  return c;
}

} // namespace cementsph::scene
