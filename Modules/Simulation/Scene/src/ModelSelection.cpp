#include "cementsph/scene/ModelSelection.h"

#include <algorithm>
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
          {"front_pore_pressure_drop_pa", n.frontPorePressurePa},
          {"mean_pore_chord_mm", n.meanPoreChordM * 1e3},
          {"particles_across_pore", n.particlesAcrossPore}};
}

PoreScale poreScaleOf(const std::vector<std::uint8_t>& solid, const std::array<int, 3>& size,
                      const std::array<double, 3>& spacingM, bool poreResolved) {
  PoreScale s;
  s.poreResolved = poreResolved;
  s.voxelSizeM = std::max({spacingM[0], spacingM[1], spacingM[2]});
  const std::size_t nx = std::size_t(size[0]), ny = std::size_t(size[1]), nz = std::size_t(size[2]);
  if (solid.size() != nx * ny * nz || solid.empty()) return s;
  // One pass in memory order (issue 23: the three axis-by-axis scans, two of them strided, were 2 % of a 5 ml
  // run on a whole-scan region): along each axis the pore length is the pore voxel count times the spacing, and a
  // run starts at every pore voxel whose predecessor along that axis is solid or outside the region.
  // Branch-free, a row at a time against the row before it (y) and the plane before it (z), a row of solid
  // standing for outside the region (a branch per voxel on a foam mispredicts half the time).
  std::size_t pores = 0, starts[3] = {0, 0, 0};
  const std::vector<std::uint8_t> outside(nx, 1);
  for (std::size_t k = 0; k < nz; ++k)
    for (std::size_t j = 0; j < ny; ++j) {
      const std::uint8_t* row = solid.data() + nx * (j + ny * k);
      const std::uint8_t* below = j > 0 ? row - nx : outside.data();
      const std::uint8_t* behind = k > 0 ? row - nx * ny : outside.data();
      // (any non-zero flag is solid)
      unsigned rowPores = 0, alongX = row[0] == 0, alongY = 0, alongZ = 0; // voxel 0 starts a run along x if pore
      for (std::size_t i = 1; i < nx; ++i) alongX += unsigned(row[i] == 0) & unsigned(row[i - 1] != 0);
      for (std::size_t i = 0; i < nx; ++i) {
        const unsigned pore = row[i] == 0;
        rowPores += pore;
        alongY += pore & unsigned(below[i] != 0);
        alongZ += pore & unsigned(behind[i] != 0);
      }
      pores += rowPores;
      starts[0] += alongX;
      starts[1] += alongY;
      starts[2] += alongZ;
    }
  const double length = double(pores) * (spacingM[0] + spacingM[1] + spacingM[2]);
  const double runs = double(starts[0] + starts[1] + starts[2]);
  s.meanPoreChordM = runs > 0 ? length / runs : 0.0;
  return s;
}

ModelChoice chooseModel(const SceneConfig& scene, double rho0, double soundSpeed, double porosity, const PoreScale& pores) {
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
  n.meanPoreChordM = pores.meanPoreChordM;
  n.particlesAcrossPore = d > 0 ? pores.meanPoreChordM / d : 0.0;
  const bool ctResolvesPores = pores.voxelSizeM > 0 && pores.meanPoreChordM >= kResolvedPoreVoxels * pores.voxelSizeM;
  const bool particlesResolvePores = n.particlesAcrossPore >= kParticlesAcrossPore;

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
  } else if (n.compression > 0.01 && pores.poreResolved && ctResolvesPores && particlesResolvePores) {
    c.pressureModel = "particle-darcy";
    c.reason = "creeping flow (" + numbers + ") in resolved pore space: the mean pore chord " +
               g3(pores.meanPoreChordM * 1e3) + " mm is " + g3(pores.meanPoreChordM / pores.voxelSizeM) +
               " voxels and " + g3(n.particlesAcrossPore) + " particle spacings (at least " + g3(kResolvedPoreVoxels) +
               " and " + g3(kParticlesAcrossPore) +
               "), so the cement is carried as incompressible particles in the pores with a free front (Darcy pressure "
               "solved on the particles, gauge Pa)";
  } else if (n.compression > 0.01) {
    c.pressureModel = "voxel-darcy";
    c.reason = "creeping flow (" + numbers + "): the equation of state would compress the cement at the Darcy pressure, so the cement is incompressible and its pressure is solved by Darcy's law on the CT's voxels (pressure in gauge Pa)";
    if (pores.poreResolved && pores.meanPoreChordM > 0)
      c.reason += !ctResolvesPores ? "; the CT does not resolve the pores (mean pore chord " +
                                         g3(pores.meanPoreChordM / pores.voxelSizeM) + " voxels, under " +
                                         g3(kResolvedPoreVoxels) + ")"
                                   : "; particles (particle-darcy) need " + g3(kParticlesAcrossPore) +
                                         " spacings across the mean pore chord " + g3(pores.meanPoreChordM * 1e3) +
                                         " mm, this particle spacing gives " + g3(n.particlesAcrossPore);
  } else {
    c.pressureModel = "equation-of-state";
    c.reason = "creeping flow with compression below 1 % (" + numbers + "): the paper's weakly compressible model is accurate";
  }
  c.reason += caveats;
  if (c.recommended.empty()) c.recommended = c.pressureModel;
  c.model = c.pressureModel == "voxel-darcy"      ? "incompressible-darcy-on-voxels"
            : c.pressureModel == "particle-darcy" ? "incompressible-darcy-on-particles-isph"
            : c.pressureModel == "incompressible" ? "incompressible-darcy-on-particles"
                                                  : "weakly-compressible";
  return c;
}

} // namespace cementsph::scene
