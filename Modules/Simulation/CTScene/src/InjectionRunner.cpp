#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/scene/AxisAlignedCT.h"

#include "InjectionOutputs.h"
#include "VoxelDarcyInjection.h"

#include "cementsph/scene/ModelSelection.h"
#include "cementsph/scene/PorousSolid.h"
#include "cementsph/scene/SimulatedCT.h"
#include "cementsph/sph/CannulaEmitter.h"
#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/Pressure/IncompressibleDarcy.h"
#include "cementsph/sph/ParticleVoxeliser.h"
#include "cementsph/sph/Presets.h"
#include "cementsph/sph/Simulation.h"
#include "cementsph/sph/TipPressureProbe.h"

#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <sstream>
#include <limits>

namespace cementsph::scene {

using nlohmann::json;

vtkSmartPointer<vtkPolyData> particlesToPolyData(const sph::FluidParticles& f, double time) {
  const vtkIdType n = vtkIdType(f.size());
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  auto make = [n](const char* name, int components) {
    auto a = vtkSmartPointer<vtkDoubleArray>::New();
    a->SetName(name);
    a->SetNumberOfComponents(components);
    a->SetNumberOfTuples(n);
    return a;
  };
  auto velocity = make("velocity_m_per_s", 3), density = make("density_kg_per_m3", 1),
       pressure = make("pressure_pa", 1), age = make("age_s", 1), viscosity = make("viscosity_pa_s", 1),
       volumeFraction = make("volume_fraction", 1), front = make("front", 1);
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  for (vtkIdType i = 0; i < n; ++i) {
    const std::size_t k = std::size_t(i);
    points->SetPoint(i, f.x[k] * 1e3, f.y[k] * 1e3, f.z[k] * 1e3);
    velocity->SetTuple3(i, f.vx[k], f.vy[k], f.vz[k]);
    density->SetValue(i, f.density[k]);
    pressure->SetValue(i, f.pressure[k]);
    age->SetValue(i, time - f.birthTime[k]);
    viscosity->SetValue(i, f.viscosity[k]);
    volumeFraction->SetValue(i, f.volumeFraction[k]);
    front->SetValue(i, f.front[k]);
    verts->InsertNextCell(1, &i);
  }
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetVerts(verts);
  poly->GetPointData()->AddArray(velocity);
  poly->GetPointData()->AddArray(density);
  poly->GetPointData()->AddArray(pressure);
  poly->GetPointData()->AddArray(age);
  poly->GetPointData()->AddArray(viscosity);
  poly->GetPointData()->AddArray(volumeFraction);
  poly->GetPointData()->AddArray(front);
  return poly;
}

namespace {


double finiteOrZero(double x) { return std::isfinite(x) ? x : 0.0; }

} // namespace

InjectionRunResult runInjection(const imaging::ImageType* input, const SceneConfig& scene, const InjectionRunOptions& o) {
  scene.validate();
  // Any orientation: an oblique CT is resampled onto an axis-aligned grid in its own patient frame.
  const imaging::ImageType::ConstPointer aligned = axisAligned(input);
  const imaging::ImageType* ct = aligned.GetPointer();
  const auto wallStart = std::chrono::steady_clock::now();
  sph::ModelPreset preset = sph::modelPreset(scene.modelPreset);
  sph::ModelParameters m = preset.model;
  if (scene.integrator) m.integrator = sph::parseIntegrator(*scene.integrator);
  if (scene.dragCoefficient) m.dragCoefficient = *scene.dragCoefficient;
  if (scene.soundSpeedMPerS) m.soundSpeed = *scene.soundSpeedMPerS;
  m.fixedSums = scene.fixedSumMethod();
  if (scene.fixedFieldSpacingOverH) m.fixedFieldSpacing = *scene.fixedFieldSpacingOverH;
  // The overdamped step moves the fastest particle at most this fraction of h. The engine's 0.05 suits
  // the Darcy box; in an injection the fastest particles are the few at the tip, and 0.05 to 0.5 gave
  // the same cement to 0.01 mm of spreading on the phantom (VALIDATION.md), so 0.25: 4x fewer steps.
  m.maxDisplacement = scene.maxDisplacementOverH.value_or(0.25);
  if (scene.neighbourSkinOverH) m.neighbourSkin = *scene.neighbourSkinOverH;
  const double d = scene.spacingM();
  m.smoothingLength = preset.hOverD * d;
  const double rho0 = m.restDensity;
  const Eigen::Vector3d tipMm = *scene.tipMm;
  const Eigen::Vector3d tip = tipMm * 1e-3;

  // The bone: pore-resolved (the paper's solid voxels) or a continuum from HU (BoneCalibration.h). Auto:
  // a continuum when the tip's voxel is above threshold_hu but not cortex, i.e. no pore is resolved there.
  std::string boneModel = scene.boneModel, boneReason = "forced by the scene key bone_model";
  if (boneModel == "auto") {
    imaging::ImageType::PointType point;
    for (unsigned a = 0; a < 3; ++a) point[a] = tipMm[int(a)];
    imaging::ImageType::IndexType index;
    boneModel = "pore-resolved";
    boneReason = "the tip's voxel is at or below threshold_hu: the CT resolves the pores (the paper's model)";
    if (ct->TransformPhysicalPointToIndex(point, index)) {
      const double hu = ct->GetPixel(index);
      if (hu > scene.thresholdHu && hu <= scene.bone.corticalHu) {
        boneModel = "continuum";
        std::ostringstream r;
        r << "the tip's voxel is " << hu << " HU, above threshold_hu " << scene.thresholdHu
          << " HU and below cortical_hu " << scene.bone.corticalHu
          << " HU: the CT does not resolve the pores there, so the bone is a continuum from HU";
        boneReason = r.str();
      }
    }
  }
  const bool continuum = boneModel == "continuum";

  PorousSolidOptions po;
  po.thresholdHu = continuum ? scene.bone.corticalHu : scene.thresholdHu; // continuum: only cortex is solid
  po.roiSizeMm = scene.roiSizeMm;
  po.reachMm = 2.0 * m.smoothingLength * 1e3;
  po.restDensity = rho0;
  po.massFactor = scene.solidMassFactor;
  po.requiredPoreVolumeMm3 = scene.volumeMl * 1e3;
  const PorousSolid solid = buildPorousSolid(ct, tipMm, po);
  const double roiVoxels = double(solid.roiSize[0]) * double(solid.roiSize[1]) * double(solid.roiSize[2]);
  const double roiPorosity = roiVoxels > 0 ? 1.0 - double(solid.solidVoxels) / roiVoxels : 1.0;
  const ModelChoice choice = chooseModel(scene, m.restDensity, m.soundSpeed, roiPorosity);
  if (o.progress) std::cerr << "inject: model " << choice.model << ": " << choice.reason << "\n";
  if (o.progress) std::cerr << "inject: bone " << boneModel << ": " << boneReason << "\n";
  if (choice.pressureModel == "voxel-darcy")
    return detail::runVoxelDarcyInjection(ct, scene, o, {preset, m, solid, choice, wallStart, continuum, boneReason, ct != input});
  if (continuum)
    throw std::invalid_argument("scene: bone_model \"continuum\" needs pressure_model \"voxel-darcy\" (got \"" +
                                choice.pressureModel + "\")");
  if (scene.hasSecondTip())
    throw std::invalid_argument("scene: second_tip_withdrawal_mm needs pressure_model \"voxel-darcy\" (the particle "
                                "models have one outlet; got \"" + choice.pressureModel + "\")");
  if (scene.viscosityLaw != "newtonian" || scene.curing().kind() != "none")
    throw std::invalid_argument("scene: viscosity_law \"" + scene.viscosityLaw + "\" and curing (curing_table, curing_model, cement) need pressure_model "
                                "\"voxel-darcy\" (the particle models are Newtonian; got \"" + choice.pressureModel + "\")");
  m.pressureModel = choice.pressureModel;
  const bool incompressible = m.pressureModel == "incompressible";

  sph::CannulaSpec spec;
  spec.tip = tip;
  spec.direction = scene.direction;
  spec.innerDiameter = scene.cannulaInnerDiameterMm * 1e-3;
  spec.flowRate = scene.flowRateM3PerS();
  spec.totalVolume = scene.volumeM3();
  spec.spacing = d;
  spec.restDensity = rho0;
  spec.buildWall = scene.cannulaWall;
  spec.wallLength = scene.cannulaLengthMm * 1e-3;
  sph::CannulaEmitter emitter(spec);
  const sph::ViscositySchedule viscosity = scene.viscositySchedule();
  m.viscosity = viscosity.at(0.0);
  m.maxTimeStep = emitter.maxTimeStep();

  sph::Domain domain;
  domain.lower = solid.lowerM;
  domain.upper = solid.upperM;
  sph::Simulation sim(m, domain);
  sim.reserveFluid(emitter.totalParticles());
  for (const Eigen::Vector3d& p : solid.positions) sim.addFixedParticle(p, solid.particleMass, solid.grid.voxelVolume());
  const std::size_t wallParticles = emitter.addWall(sim);
  sph::TipPressureProbe probe(
      sph::TipPressureProbe::ringAroundTip(tip, spec.direction, 0.5 * spec.innerDiameter, 6, d));
  // The incompressible model's source: the flow enters the cement within sourceRadius of the outlet.
  const double sourceRadius = 0.5 * spec.innerDiameter + 0.5 * d;
  if (incompressible) sim.setVolumeSource({tip, sourceRadius, spec.flowRate});
  const double cannulaLength = scene.cannulaLengthMm * 1e-3;
  // Pressure at the outlet [Pa]: incompressible, the mean pressure of the cement the source feeds (the
  // pressure the cannula works against: power = Q p); equation of state, the paper's probe (Eq. 6 ring).
  std::vector<detail::TipRecord> tipSeries;
  auto outletPressure = [&]() {
    if (!incompressible) return probe.sample(sim).meanPressure;
    const sph::FluidParticles& f = sim.fluid();
    double sum = 0, weight = 0;
    for (std::size_t i = 0; i < f.size(); ++i)
      if ((f.position(i) - tip).norm() <= sourceRadius) {
        const double w = f.mass[i] / f.porosity[i];
        sum += w * f.pressure[i];
        weight += w;
      }
    return weight > 0 ? sum / weight : 0.0;
  };
  // Cement volume: sum of m / rho with each particle's own density [m^3].
  auto cementVolume = [&]() {
    const sph::FluidParticles& f = sim.fluid();
    double v = 0;
    for (std::size_t i = 0; i < f.size(); ++i) v += f.mass[i] / f.density[i];
    return v;
  };
  // Injected against held volume now (volume_history in metrics.json).
  auto volumeRecord = [&]() {
    return json{{"time_s", sim.time()}, {"volume_injected_ml", emitter.emittedVolume() * 1e6},
                {"cement_volume_ml", cementVolume() * 1e6}};
  };
  json volumeHistory = json::array();

  const sph::ParticleVoxeliser voxeliser(solid.grid, 2.0 * scene.particleRadiusMm * 1e-3); // h = 2r
  detail::InjectionWriter writer(o.outDir, scene, o.huPerRelativeDensity, [&] {
    return simulatedCtOnRoi(ct, solid, voxeliser.density(sim.fluid()), o.huPerRelativeDensity, rho0);
  });
  auto writeSnapshot = [&]() {
    volumeHistory.push_back(volumeRecord());
    if (writer.writing()) writer.snapshot(sim.time(), particlesToPolyData(sim.fluid(), sim.time()));
  };

  const double T = scene.injectionDurationS();
  detail::InjectionProgress progress(o, wallStart, T);
  double nextSnapshot = scene.snapshotIntervalS;
  bool stopped = false;
  while (sim.time() < T) {
    viscosity.apply(sim, spec.startTime);
    emitter.emit(sim);
    sim.step();
    {
      const double tipPa = outletPressure();
      const double mu = sim.parameters().viscosity;
      tipSeries.push_back({sim.time(), tipPa,
                           sph::hagenPoiseuillePressureDrop(mu, cannulaLength, spec.flowRate, spec.innerDiameter)});
    }
    if (sim.time() >= nextSnapshot && sim.time() < T) {
      writeSnapshot();
      while (nextSnapshot <= sim.time()) nextSnapshot += scene.snapshotIntervalS;
    }
    if (!progress.step(sim.time(), [&] {
          return std::to_string(sim.fluid().size()) + " fluid + " + std::to_string(sim.fixed().size()) +
                 " fixed particles, " + std::to_string(sim.statistics().steps) + " steps";
        })) {
      stopped = true;
      break;
    }
  }
  if (!stopped) emitter.emit(sim); // the emission up to the end time
  sim.updateDensityAndPressure();
  progress.done();
  const double wallS = progress.wallSeconds();

  // Figures.
  const sph::FluidParticles& f = sim.fluid();
  double fluidMass = 0, spread = 0;
  std::size_t inSolid = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    fluidMass += f.mass[i];
    spread += (f.position(i) - tip).norm();
    std::array<int, 3> ijk{};
    if (solid.voxelOf(f.position(i), ijk) && solid.solid[solid.grid.index(ijk[0], ijk[1], ijk[2])]) ++inSolid;
  }
  if (f.size() > 0) spread /= double(f.size());
  const double emittedMass = double(emitter.emittedCount()) * emitter.particleMass();
  const double escapedMass = double(sim.escapedCount()) * emitter.particleMass();
  const double massBalance = emittedMass > 0 ? (emittedMass - fluidMass - escapedMass) / emittedMass : 0.0;
  double finalPressure = std::numeric_limits<double>::quiet_NaN(), maxPressure = finalPressure, baseline = 0.0;
  double maxInjection = 0.0;
  bool haveBaseline = false;
  if (!tipSeries.empty()) {
    finalPressure = tipSeries.back().tipPa;
    maxPressure = -std::numeric_limits<double>::infinity();
    for (const auto& s : tipSeries) {
      maxPressure = std::max(maxPressure, s.tipPa);
      maxInjection = std::max(maxInjection, s.tipPa + s.cannulaPa);
    }
    if (!incompressible) { // the paper's baseline: the mean of the first 0.5 s (model pressure is relative)
      try {
        baseline = probe.baseline();
        haveBaseline = true;
      } catch (const std::logic_error&) {
      }
    }
  }
  const double finalCannula = tipSeries.empty() ? 0.0 : tipSeries.back().cannulaPa;

  // Simulated CT on the CT's grid within the ROI.
  const auto simCt = simulatedCtOnRoi(ct, solid, voxeliser.density(f), o.huPerRelativeDensity, rho0);

  const auto& st = sim.statistics();
  json metrics;
  metrics["volume_injected_ml"] = emitter.emittedVolume() * 1e6;
  metrics["volume_requested_ml"] = scene.volumeMl;
  metrics["simulated_time_s"] = sim.time();
  metrics["stopped_early"] = stopped;
  metrics["fluid_particles"] = f.size();
  metrics["fixed_particles"] = sim.fixed().size();
  metrics["cannula_wall_particles"] = wallParticles;
  metrics["solid_voxels_kept"] = solid.keptVoxels;
  metrics["solid_voxels_total"] = solid.solidVoxels;
  metrics["solid_mass_factor"] = scene.solidMassFactor;
  metrics["connected_pore_voxels"] = solid.connectedPoreVoxels;
  metrics["roi_voxels"] = {solid.roiSize[0], solid.roiSize[1], solid.roiSize[2]};
  metrics["roi_start_index"] = {solid.roiStart[0], solid.roiStart[1], solid.roiStart[2]}; // relative to the CT region start
  metrics["steps"] = st.steps;
  metrics["smallest_time_step_s"] = st.smallestStep;
  metrics["largest_time_step_s"] = st.largestStep;
  metrics["wall_time_s"] = wallS;
  metrics["real_time_factor"] = wallS > 0 ? sim.time() / wallS : 0.0; // simulated seconds per wall second
  metrics["integrator"] = sph::toString(m.integrator);
  metrics["fixed_particle_sums"] = sph::toString(m.fixedSums);
  metrics["fixed_field_bricks"] = sim.fixedField().bricksFilled();
  metrics["neighbour_rebuilds"] = st.neighbourRebuilds;
  metrics["neighbour_relistings"] = st.relistings;
  metrics["model_preset"] = preset.name;
  metrics["ct_resampled_to_axis_aligned"] = ct != input;
  metrics["model"] = choice.model;
  metrics["model_reason"] = choice.reason;
  metrics["recommended_pressure_model"] = choice.recommended;
  metrics["pressure_model"] = m.pressureModel;
  metrics["resistance"] = m.resistanceName();
  metrics["viscosity_law"] = m.viscosityLaw;
  metrics["dimensionless_numbers"] = choice.numbersJson();
  metrics["pressure_is_physical"] = incompressible; // gauge Pa; the weakly compressible pressure is the model's
  metrics["cannula_pressure_drop_pa"] = finalCannula;
  metrics["injection_pressure_pa"] = finiteOrZero(finalPressure) + finalCannula;
  metrics["max_injection_pressure_pa"] = maxInjection;
  metrics["cement_volume_ml"] = cementVolume() * 1e6;
  {
    json history = volumeHistory; // at every snapshot, and the final state
    history.push_back(volumeRecord());
    metrics["volume_history"] = history;
  }
  if (incompressible) {
    const auto* darcy = dynamic_cast<const sph::IncompressibleDarcy*>(&sim.pressureModel());
    const auto& ps = darcy->statistics();
    metrics["pressure_solves"] = ps.solves;
    metrics["pressure_solver_iterations_mean"] = ps.solves ? double(ps.iterations) / double(ps.solves) : 0.0;
    metrics["pressure_solver_worst_residual"] = ps.worstResidual;
    metrics["pressure_solver_unconverged"] = ps.unconverged;
    metrics["pressure_solve_wall_s"] = ps.solveSeconds;
    metrics["front_particles"] = ps.lastFrontParticles;
    metrics["outlet_source_radius_mm"] = sourceRadius * 1e3;
  }
  metrics["smoothing_length_mm"] = m.smoothingLength * 1e3;
  metrics["final_tip_pressure_pa"] = finiteOrZero(finalPressure);
  metrics["max_tip_pressure_pa"] = finiteOrZero(maxPressure);
  metrics["tip_pressure_baseline_pa"] = baseline;
  metrics["mean_spreading_distance_mm"] = spread * 1e3;
  metrics["escaped_particles"] = sim.escapedCount();
  metrics["mass_balance_error"] = massBalance;
  metrics["fluid_in_solid_fraction"] = f.size() == 0 ? 0.0 : double(inSolid) / double(f.size());
  metrics["simulated_ct_hu_per_relative_density"] = o.huPerRelativeDensity;
  metrics["final_viscosity_pa_s"] = sim.parameters().viscosity;

  InjectionRunResult result;
  result.particles = particlesToPolyData(f, sim.time());
  result.simulatedCt = simCt;
  std::optional<double> csvBaseline; // the pressure itself where it is physical, else relative to the baseline
  if (incompressible) csvBaseline = 0.0;
  else if (haveBaseline) csvBaseline = baseline;
  writer.finish(sim.time(), result.particles, simCt, tipSeries, csvBaseline, metrics);
  result.metrics = metrics;
  return result;
}

} // namespace cementsph::scene
