#include "cementsph/phantom/PhantomNumerics.h"

#include "cementsph/sph/Presets.h"

#include <sstream>
#include <stdexcept>

namespace cementsph::phantom {

scene::SceneConfig phantomInjectionScene(const PhantomNumerics& n, const std::array<double, 3>& tipMm, double volumeMl,
                                         double viscosityPaS, double flowRateMlPerS) {
  scene::SceneConfig sc = scene::scenePreset("paper");
  sc.modelPreset = n.modelPreset;
  sc.particleRadiusMm = n.particleRadiusMm;
  sc.tipMm = Eigen::Vector3d(tipMm[0], tipMm[1], tipMm[2]);
  sc.direction = Eigen::Vector3d::UnitZ();
  sc.cannulaInnerDiameterMm = n.cannulaInnerDiameterMm;
  sc.cannulaLengthMm = n.cannulaLengthMm;
  sc.cannulaWall = n.cannulaWall;
  sc.flowRateMlPerS = flowRateMlPerS;
  sc.volumeMl = volumeMl;
  sc.viscosityPaS = viscosityPaS;
  sc.viscosityRatePaPerS.reset();
  sc.viscosityTable.clear();
  sc.thresholdHu = n.thresholdHu;
  sc.roiSizeMm = n.roiSizeMm;
  sc.snapshotIntervalS = 1e9; // no snapshots: only the final simulated CT is used
  sc.simulatedCtSnapshots = false;
  sc.solidMassFactor = n.solidMassFactor;
  sc.dragCoefficient = n.dragCoefficient;
  sc.soundSpeedMPerS = n.soundSpeedMPerS;
  sc.integrator = n.integrator;
  sc.pressureModel = n.pressureModel;
  sc.fixedParticleSums = n.fixedParticleSums;
  sc.fixedFieldSpacingOverH.reset(); // exact sums use no table
  sc.maxDisplacementOverH = n.maxDisplacementOverH;
  sc.neighbourSkinOverH = n.neighbourSkinOverH;
  sc.validate();
  return sc;
}

void checkModelPreset(const PhantomNumerics& n) {
  const sph::ModelPreset p = sph::modelPreset(n.modelPreset);
  auto mismatch = [&](const std::string& what, const std::string& pinned, const std::string& preset) {
    throw std::runtime_error("phantom: model preset '" + n.modelPreset + "' has " + what + " " + preset +
                             " where the phantom's numerics pin " + pinned +
                             " (Modules/Simulation/Phantom/PhantomNumerics.h: name the preset that keeps the "
                             "phantom's model, or regenerate Data/foam-phantom on purpose)");
  };
  auto text = [](double x) {
    std::ostringstream s;
    s << x;
    return s.str();
  };
  if (p.hOverD != n.hOverD) mismatch("h/d", text(n.hOverD), text(p.hOverD));
  if (p.model.restDensity != n.restDensityKgPerM3)
    mismatch("rest density [kg/m^3]", text(n.restDensityKgPerM3), text(p.model.restDensity));
  if (sph::toString(p.model.viscosityModel) != n.viscosityModel)
    mismatch("viscosity model", n.viscosityModel, sph::toString(p.model.viscosityModel));
  if (p.model.overdampedStability != n.overdampedStability)
    mismatch("overdamped stability number", text(n.overdampedStability), text(p.model.overdampedStability));
  if (p.model.relisting != n.relisting)
    mismatch("relisting", n.relisting ? "on" : "off", p.model.relisting ? "on" : "off");
}

nlohmann::json toJson(const PhantomNumerics& n) {
  return {{"model_preset", n.modelPreset},
          {"h_over_d", n.hOverD},
          {"rest_density_kg_per_m3", n.restDensityKgPerM3},
          {"viscosity_model", n.viscosityModel},
          {"overdamped_stability", n.overdampedStability},
          {"neighbour_skin_over_h", n.neighbourSkinOverH},
          {"relisting", n.relisting},
          {"integrator", n.integrator},
          {"pressure_model", n.pressureModel},
          {"drag_coefficient", n.dragCoefficient},
          {"sound_speed_m_per_s", n.soundSpeedMPerS},
          {"fixed_particle_sums", n.fixedParticleSums},
          {"max_displacement_over_h", n.maxDisplacementOverH},
          {"particle_radius_mm", n.particleRadiusMm},
          {"cannula_inner_diameter_mm", n.cannulaInnerDiameterMm},
          {"cannula_length_mm", n.cannulaLengthMm},
          {"cannula_wall", n.cannulaWall},
          {"threshold_hu", n.thresholdHu},
          {"roi_size_mm", n.roiSizeMm},
          {"solid_mass_factor", n.solidMassFactor},
          {"simulated_ct_hu_per_relative_density", n.huPerRelativeDensity}};
}

} // namespace cementsph::phantom
