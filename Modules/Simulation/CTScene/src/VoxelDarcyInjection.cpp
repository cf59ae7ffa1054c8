#include "VoxelDarcyInjection.h"

#include "InjectionOutputs.h"

#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/SimulatedCT.h"
#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/Simulation.h"
#include "cementsph/sph/TubeFlow.h"
#include "cementsph/voxeldarcy/VoxelDarcyFilling.h"

#include <itkImage.h>
#include <itkSignedMaurerDistanceMapImageFilter.h>
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <vector>
#include <limits>
#include <memory>
#include <stdexcept>

namespace cementsph::scene::detail {

using nlohmann::json;
using voxeldarcy::VoxelDarcyFilling;
using voxeldarcy::VoxelMedium;

namespace {

// The cannula's wall thickness [m] where the scene gives none: 11G regular wall, outer 3.048 mm against
// inner 2.388 mm (ISO 9626).
constexpr double kCannulaWallM = 0.33e-3;


// Capillary entry pressure of each pore voxel [Pa]: Young-Laplace for the cement entering a pore of the
// local radius r as the non-wetting phase (cos theta = 1, the largest entry pressure), p_e = 2 sigma / r.
// r is the distance from the voxel's centre to the solid's surface: the Euclidean distance to the nearest
// solid voxel centre (ITK's signed Maurer distance map, in mm) less half a voxel, at least half a voxel.
std::vector<float> capillaryEntryPressure(const PorousSolid& solid, double tensionNPerM) {
  using Mask = itk::Image<unsigned char, 3>;
  using Distance = itk::Image<float, 3>;
  auto mask = Mask::New();
  Mask::RegionType region;
  Mask::SizeType size;
  for (unsigned a = 0; a < 3; ++a) size[a] = itk::SizeValueType(solid.grid.size[int(a)]);
  region.SetSize(size);
  mask->SetRegions(region);
  Mask::SpacingType spacing;
  for (unsigned a = 0; a < 3; ++a) spacing[a] = solid.grid.spacing[int(a)] * 1e3;
  mask->SetSpacing(spacing);
  mask->Allocate();
  std::copy(solid.solid.begin(), solid.solid.end(), mask->GetBufferPointer());
  const double half = 0.5 * solid.grid.spacing.minCoeff() * 1e3; // mm
  std::vector<float> entry(solid.grid.count(), 0.0f);
  if (solid.solidVoxels == 0) return entry; // no solid: no throats
  auto distance = itk::SignedMaurerDistanceMapImageFilter<Mask, Distance>::New();
  distance->SetInput(mask);
  distance->SetBackgroundValue(0);
  distance->SetInsideIsPositive(false);
  distance->SetSquaredDistance(false);
  distance->SetUseImageSpacing(true);
  distance->Update();
  const float* d = distance->GetOutput()->GetBufferPointer();
  for (std::size_t c = 0; c < entry.size(); ++c) {
    if (solid.solid[c]) continue;
    const double rMm = std::max(double(d[c]) - half, half); // d: to the nearest solid voxel's centre
    entry[c] = float(2.0 * tensionNPerM / (rMm * 1e-3));
  }
  return entry;
}

// Cement in soft tissue, by 6-connected site: volume-weighted centre (mm, the CT's frame), first arrival
// (s) and volume (ml). Returns the total leaked volume [m^3].
double leakage(const VoxelDarcyFilling& f, const std::vector<std::uint8_t>& softTissue, nlohmann::json* sites) {
  const VoxelMedium& m = f.medium();
  double total = 0;
  std::vector<std::uint8_t> seen(softTissue.empty() ? 0 : m.count(), 0);
  if (sites) *sites = nlohmann::json::array();
  for (std::size_t c = 0; c < softTissue.size(); ++c) {
    if (!softTissue[c] || f.fill()[c] <= 0 || seen[c]) continue;
    double volume = 0, first = std::numeric_limits<double>::infinity();
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    std::vector<std::size_t> stack{c};
    seen[c] = 1;
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      const double vol = f.fill()[v] * m.porosity[v] * m.voxelVolume();
      volume += vol;
      centre += vol * m.centre(v);
      first = std::min(first, f.arrivalTime()[v]);
      const auto ijk = m.ijk(v);
      const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
      for (const auto& s : d) {
        const int i = ijk[0] + s[0], j = ijk[1] + s[1], k = ijk[2] + s[2];
        if (i < 0 || j < 0 || k < 0 || i >= m.size[0] || j >= m.size[1] || k >= m.size[2]) continue;
        const std::size_t n = m.index(i, j, k);
        if (softTissue[n] && f.fill()[n] > 0 && !seen[n]) {
          seen[n] = 1;
          stack.push_back(n);
        }
      }
    }
    total += volume;
    if (sites) {
      const Eigen::Vector3d mm = centre / volume * 1e3;
      sites->push_back({{"position_mm", {mm.x(), mm.y(), mm.z()}}, {"first_time_s", first}, {"volume_ml", volume * 1e6}});
    }
  }
  return total;
}

// One point per voxel holding cement.
vtkSmartPointer<vtkPolyData> cementVoxelsToPolyData(const VoxelDarcyFilling& f, double restDensity) {
  const VoxelMedium& m = f.medium();
  std::vector<std::size_t> cells;
  for (std::size_t c = 0; c < m.count(); ++c)
    if (f.fill()[c] > 0) cells.push_back(c);
  const vtkIdType n = vtkIdType(cells.size());
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToFloat(); // mm to 1e-4 of a 40 mm region; half the bytes of doubles
  points->SetNumberOfPoints(n);
  // Single precision (half the bytes to write a hundred times a run), but the fill and the volumes in double:
  // they add up to the injected volume.
  auto make = [n](const char* name, int components, bool doublePrecision = false) {
    vtkSmartPointer<vtkDataArray> a;
    if (doublePrecision) a = vtkSmartPointer<vtkDoubleArray>::New();
    else a = vtkSmartPointer<vtkFloatArray>::New();
    a->SetName(name);
    a->SetNumberOfComponents(components);
    a->SetNumberOfTuples(n);
    return a;
  };
  auto fill = make("fill_fraction", 1, true), volume = make("cement_volume_mm3", 1, true), pressure = make("pressure_pa", 1),
       velocity = make("darcy_velocity_m_per_s", 3), viscosity = make("viscosity_pa_s", 1),
       porosity = make("porosity", 1), permeability = make("permeability_m2", 1), arrival = make("arrival_time_s", 1),
       age = make("age_s", 1), speed = make("velocity_m_per_s", 3), density = make("density_kg_per_m3", 1);
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  for (vtkIdType i = 0; i < n; ++i) {
    const std::size_t c = cells[std::size_t(i)];
    const Eigen::Vector3d x = m.centre(c) * 1e3;
    points->SetPoint(i, x.x(), x.y(), x.z());
    fill->SetTuple1(i, f.fill()[c]);
    volume->SetTuple1(i, f.fill()[c] * m.porosity[c] * m.voxelVolume() * 1e9);
    pressure->SetTuple1(i, f.pressure()[c]);
    const Eigen::Vector3d q = f.darcyVelocity(c);
    velocity->SetTuple3(i, q.x(), q.y(), q.z());
    const Eigen::Vector3d v = q / double(m.porosity[c]); // the cement's own (interstitial) velocity
    speed->SetTuple3(i, v.x(), v.y(), v.z());
    density->SetTuple1(i, restDensity);
    viscosity->SetTuple1(i, f.viscosity()[c]);
    porosity->SetTuple1(i, m.porosity[c]);
    permeability->SetTuple1(i, m.permeability[c]);
    arrival->SetTuple1(i, f.arrivalTime()[c]);
    age->SetTuple1(i, f.time() - f.arrivalTime()[c]);
    verts->InsertNextCell(1, &i);
  }
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetVerts(verts);
  for (auto* a : {fill.Get(), volume.Get(), pressure.Get(), velocity.Get(), viscosity.Get(), porosity.Get(),
                  permeability.Get(), arrival.Get(), age.Get(), speed.Get(), density.Get()})
    poly->GetPointData()->AddArray(a);
  return poly;
}

} // namespace

InjectionRunResult runVoxelDarcyInjection(const imaging::ImageType* ct, const SceneConfig& scene,
                                          const InjectionRunOptions& o, const VoxelDarcyRunInputs& in) {
  const PorousSolid& solid = in.solid;
  const sph::ModelParameters& model = in.model;
  const double rho0 = model.restDensity;
  const Eigen::Vector3d tip = *scene.tipMm * 1e-3;
  const Eigen::Vector3d axis = scene.direction.normalized();
  const double innerDiameter = scene.cannulaInnerDiameterMm * 1e-3, cannulaLength = scene.cannulaLengthMm * 1e-3;
  const double flowRate = scene.flowRateM3PerS();

  // The medium: the CT's pore voxels open, its solid voxels closed. A resolved pore voxel has the
  // permeability of the model preset's drag in open space, k0 = h^5 / (Cf d^3) (model-notes 3: the
  // paper's Eq. 9 resistance with no solid near), unless the scene gives pore_permeability_m2.
  const double d = scene.spacingM(), h = model.smoothingLength;
  const double poreK = scene.porePermeabilityM2.value_or(std::pow(h, 5) / (model.dragCoefficient * d * d * d));
  if (!(poreK >= 1e-18 && poreK <= 1e-3))
    throw std::invalid_argument("scene: the pore permeability k0 = h^5 / (Cf d^3) = " + std::to_string(poreK) +
                                " m^2 from particle_radius_mm and the preset is outside 1e-18 .. 1e-3 m^2 (give "
                                "pore_permeability_m2, or a particle radius of a pore's scale)");
  VoxelMedium medium;
  medium.size = solid.grid.size;
  medium.origin = solid.grid.origin;
  medium.spacing = solid.grid.spacing;
  medium.porosity.assign(medium.count(), 1.0f);
  medium.permeability.assign(medium.count(), poreK);
  std::vector<std::uint8_t> softTissue; // continuum: voxels outside bone, where cement is leakage
  if (in.continuum) {
    // Each voxel's porosity and permeability from its HU (BoneCalibration.h).
    softTissue.assign(medium.count(), 0);
    const auto start = ct->GetLargestPossibleRegion().GetIndex();
    for (std::size_t c = 0; c < medium.count(); ++c) {
      const auto v = medium.ijk(c);
      imaging::ImageType::IndexType idx;
      for (unsigned a = 0; a < 3; ++a) idx[a] = start[a] + solid.roiStart[a] + v[a];
      const double hu = ct->GetPixel(idx);
      medium.porosity[c] = float(scene.bone.porosity(hu));
      medium.permeability[c] = scene.bone.permeability(hu);
      softTissue[c] = scene.bone.tissue(hu) == BoneCalibration::Tissue::SoftTissue;
    }
  } else {
    for (std::size_t c = 0; c < medium.count(); ++c)
      if (solid.solid[c]) medium.porosity[c] = 0.0f;
  }
  // The cannula's shaft behind the outlet is closed (cement cannot flow back into or along it): voxels more
  // than half a voxel behind the outlet plane, so that the voxel holding the tip stays open wherever the tip
  // falls within it.
  std::size_t shaftVoxels = 0;
  // With a second tip, the stretch of the shaft between the two outlets opens when the cannula is withdrawn:
  // those voxels, with their own porosity and permeability.
  const double withdrawal = scene.hasSecondTip() ? *scene.secondTipWithdrawalMm * 1e-3 : 0.0;
  std::vector<std::size_t> tractVoxels;
  std::vector<float> tractPorosity;
  std::vector<double> tractPermeability;
  if (scene.cannulaWall) {
    const double outer = 0.5 * innerDiameter + kCannulaWallM;
    const double behind = 0.5 * solid.grid.spacing.maxCoeff();
    for (std::size_t c = 0; c < medium.count(); ++c) {
      const Eigen::Vector3d r = medium.centre(c) - tip;
      const double s = r.dot(axis);
      if (s < -behind && s >= -cannulaLength && (r - s * axis).norm() <= outer && medium.porosity[c] > 0) {
        if (withdrawal > 0 && s + withdrawal >= -behind) {
          tractVoxels.push_back(c);
          tractPorosity.push_back(medium.porosity[c]);
          tractPermeability.push_back(medium.permeability[c]);
        }
        medium.porosity[c] = 0.0f;
        ++shaftVoxels;
      }
    }
  }
  const double sourceRadius = std::max(0.5 * innerDiameter, 0.5 * solid.grid.spacing.minCoeff());

  VoxelDarcyFilling filling(std::move(medium));
  filling.setSource(tip, sourceRadius);
  if (scene.capillaryTensionNPerM > 0) filling.setEntryPressure(capillaryEntryPressure(solid, scene.capillaryTensionNPerM));
  const sph::ViscositySchedule viscosity = scene.viscositySchedule();
  // The cement's law: Newtonian (the schedule) or shear-thinning, times the curing factor.
  const bool shearThinning = scene.viscosityLaw != "newtonian";
  const std::shared_ptr<const sph::Rheology> law = sph::makeRheology(scene.viscosityLaw, scene.rheology);
  const double lower = scene.rheology.minimumViscosityPaS, upper = scene.rheology.maximumViscosityPaS;
  double cachedFactor = -1, cachedCannula = 0;
  auto cannulaDrop = [&](double factor, double mu) {
    if (!shearThinning) return sph::hagenPoiseuillePressureDrop(mu, cannulaLength, flowRate, innerDiameter);
    if (factor != cachedFactor) { // the general integral takes ~20 ms: once per curing factor
      if (scene.viscosityLaw == "power-law") {
        cachedCannula = sph::powerLawTubePressureDrop(factor * scene.rheology.consistencyPaSn, scene.rheology.flowIndex,
                                                      cannulaLength, flowRate, innerDiameter);
      } else {
        sph::RheologyParameters p = scene.rheology;
        p.zeroShearViscosityPaS *= factor;
        p.infiniteShearViscosityPaS *= factor;
        cachedCannula = sph::tubePressureDrop(*sph::makeRheology(scene.viscosityLaw, p), cannulaLength, flowRate,
                                              innerDiameter);
      }
      cachedFactor = factor;
    }
    return cachedCannula;
  };

  std::vector<TipRecord> tipSeries;
  json volumeHistory = json::array();
  auto volumeRecord = [&]() {
    return json{{"time_s", filling.time()}, {"volume_injected_ml", filling.injectedVolume() * 1e6},
                {"cement_volume_ml", filling.cementVolume() * 1e6}};
  };
  auto cementDensity = [&]() { // kg/m^3 of cement per ROI voxel (its filled pore fraction at rho0)
    std::vector<double> rho(filling.medium().count(), 0.0);
    for (std::size_t c = 0; c < rho.size(); ++c) rho[c] = filling.fill()[c] * filling.medium().porosity[c] * rho0;
    return rho;
  };

  InjectionWriter writer(o.outDir, scene, o.huPerRelativeDensity,
                         [&] { return simulatedCtOnRoi(ct, solid, cementDensity(), o.huPerRelativeDensity, rho0); });
  auto writeSnapshot = [&]() {
    volumeHistory.push_back(volumeRecord());
    if (writer.writing()) writer.snapshot(filling.time(), cementVoxelsToPolyData(filling, rho0));
  };

  const double T = scene.injectionDurationS();
  const double endTime = T * (1 - 1e-12);
  InjectionProgress progress(o, in.wallStart, T);
  double nextSnapshot = scene.snapshotIntervalS;
  bool stopped = false, stoppedAtLeak = false;
  // The second tip's start (never, with one tip).
  const double secondTipStart = scene.hasSecondTip() ? scene.secondTipStartS() : 2 * T;
  bool atSecondTip = !scene.hasSecondTip();
  try {
    while (filling.time() < endTime) {
      const double factor = scene.curingFactor(filling.time());
      const double mu = std::clamp(factor * viscosity.at(filling.time()), lower, upper);
      if (shearThinning)
        filling.setShearRateViscosity(
            [law, factor, lower, upper](double g) { return std::clamp(factor * law->unbounded(g), lower, upper); },
            law->flowIndex(), 3);
      else
        filling.setViscosity(mu);
      // At most 1 % of the injection per step: progress every 1 % and a tip-pressure curve with 100 points.
      double dtMax = std::min(T - filling.time(), 0.01 * T);
      if (nextSnapshot - filling.time() > 1e-9 * T) dtMax = std::min(dtMax, nextSnapshot - filling.time());
      if (!atSecondTip && secondTipStart - filling.time() > 1e-9 * T) dtMax = std::min(dtMax, secondTipStart - filling.time());
      filling.step(flowRate, dtMax);
      if (!atSecondTip && filling.time() >= secondTipStart * (1 - 1e-12)) {
        // The cannula is withdrawn: its tract opens, and the outlet is the second tip from now on.
        filling.openVoxels(tractVoxels, tractPorosity, tractPermeability);
        try {
          filling.setSource(tip - withdrawal * axis, sourceRadius);
        } catch (const std::invalid_argument& e) {
          throw std::invalid_argument("scene: the second tip, second_tip_withdrawal_mm back along the axis: " +
                                      std::string(e.what()));
        }
        atSecondTip = true;
      }
      tipSeries.push_back({filling.time(), filling.sourcePressure(), cannulaDrop(factor, mu)});
      // A surgeon stops at the first leak (1 mm^3 of cement outside bone).
      if (scene.stopAtFirstLeak && !softTissue.empty() && leakage(filling, softTissue, nullptr) > 1e-9) {
        stoppedAtLeak = true;
        stopped = true;
        break;
      }
      if (filling.time() >= nextSnapshot * (1 - 1e-12) && filling.time() < endTime) {
        writeSnapshot();
        while (nextSnapshot <= filling.time() * (1 + 1e-12)) nextSnapshot += scene.snapshotIntervalS;
      }
      if (!progress.step(filling.time(), [&] {
            return std::to_string(filling.statistics().lastUnknowns) + " filled voxels, " +
                   std::to_string(filling.statistics().steps) + " steps";
          })) {
        stopped = true;
        break;
      }
    }
  } catch (const voxeldarcy::FillingError& e) {
    throw sph::SimulationError(e.what()); // a failed run, as an unstable particle run
  }
  progress.done();
  const double wallS = progress.wallSeconds();

  // Figures.
  const VoxelMedium& m = filling.medium();
  double spread = 0, held = 0;
  std::size_t cementVoxels = 0;
  for (std::size_t c = 0; c < m.count(); ++c) {
    const double v = filling.fill()[c] * m.porosity[c];
    if (v <= 0) continue;
    ++cementVoxels;
    spread += v * (m.centre(c) - tip).norm();
    held += v;
  }
  if (held > 0) spread /= held;
  double finalPressure = 0, maxPressure = 0, maxInjection = 0, finalCannula = 0;
  for (const auto& s : tipSeries) {
    maxPressure = std::max(maxPressure, s.tipPa);
    maxInjection = std::max(maxInjection, s.tipPa + s.cannulaPa);
  }
  if (!tipSeries.empty()) {
    finalPressure = tipSeries.back().tipPa;
    finalCannula = tipSeries.back().cannulaPa;
  }
  const auto simCt = simulatedCtOnRoi(ct, solid, cementDensity(), o.huPerRelativeDensity, rho0);
  std::size_t sourceVoxels = filling.sourceVoxels().size();
  double porosityAtTip = 0, permeabilityAtTip = 0;
  for (std::size_t c : filling.sourceVoxels()) {
    porosityAtTip += m.porosity[c] / double(sourceVoxels);
    permeabilityAtTip += m.permeability[c] / double(sourceVoxels);
  }

  const auto& st = filling.statistics();
  json metrics;
  metrics["volume_injected_ml"] = filling.injectedVolume() * 1e6;
  metrics["volume_requested_ml"] = scene.volumeMl;
  metrics["simulated_time_s"] = filling.time();
  metrics["stopped_early"] = stopped;
  if (scene.hasSecondTip()) {
    const Eigen::Vector3d second = scene.secondTipMm();
    metrics["second_tip_mm"] = {second.x(), second.y(), second.z()};
    metrics["second_tip_start_s"] = secondTipStart;
    metrics["second_tip_volume_ml"] = scene.secondTipVolumeMl;
  }
  metrics["fluid_particles"] = cementVoxels; // the points of particles_NNNN.vtp: one per voxel holding cement
  metrics["cement_voxels"] = cementVoxels;
  metrics["fixed_particles"] = 0;
  metrics["cannula_wall_particles"] = 0;
  metrics["cannula_shaft_voxels_closed"] = shaftVoxels;
  metrics["solid_voxels_kept"] = solid.solidVoxels;
  metrics["solid_voxels_total"] = solid.solidVoxels;
  metrics["connected_pore_voxels"] = solid.connectedPoreVoxels;
  metrics["roi_voxels"] = {solid.roiSize[0], solid.roiSize[1], solid.roiSize[2]};
  metrics["roi_start_index"] = {solid.roiStart[0], solid.roiStart[1], solid.roiStart[2]};
  metrics["steps"] = st.steps;
  metrics["wall_time_s"] = wallS;
  metrics["real_time_factor"] = wallS > 0 ? filling.time() / wallS : 0.0;
  metrics["model_preset"] = in.preset.name;
  metrics["ct_resampled_to_axis_aligned"] = in.resampled;
  metrics["model"] = in.choice.model;
  metrics["model_reason"] = in.choice.reason;
  metrics["recommended_pressure_model"] = in.choice.recommended;
  metrics["pressure_model"] = "voxel-darcy";
  metrics["resistance"] = in.continuum              ? "continuum permeability from HU (Kozeny-Carman)"
                          : scene.porePermeabilityM2 ? "pore-permeability (scene)"
                                                     : "pore-permeability (preset drag k0)";
  metrics["viscosity_law"] = scene.viscosityLaw;
  {
    double lo = std::numeric_limits<double>::infinity(), hi = 0;
    for (std::size_t c = 0; c < m.count(); ++c)
      if (filling.filled(c)) {
        lo = std::min(lo, filling.viscosity()[c]);
        hi = std::max(hi, filling.viscosity()[c]);
      }
    metrics["apparent_viscosity_min_pa_s"] = std::isfinite(lo) ? lo : 0.0;
    metrics["apparent_viscosity_max_pa_s"] = hi;
    metrics["curing_factor_at_end"] = scene.curingFactor(filling.time());
    metrics["curing_factor_at_start"] = scene.curingFactor(0.0);
    metrics["curing_model"] = scene.curing().kind();
  }
  metrics["dimensionless_numbers"] = in.choice.numbersJson();
  metrics["pressure_is_physical"] = true;
  metrics["pore_permeability_m2"] = poreK;
  metrics["porosity_at_tip"] = porosityAtTip;
  metrics["bone_model"] = in.continuum ? "continuum" : "pore-resolved";
  metrics["bone_model_reason"] = in.boneModelReason;
  if (in.continuum) {
    json sites;
    metrics["leakage_volume_ml"] = leakage(filling, softTissue, &sites) * 1e6;
    metrics["leakage_sites"] = sites;
    metrics["leakage_assessed"] = true;
    metrics["stopped_at_first_leak"] = stoppedAtLeak;
    metrics["bone_calibration"] = {{"marrow_hu", scene.bone.marrowHu},
                                   {"bone_tissue_hu", scene.bone.boneTissueHu},
                                   {"kozeny_carman_diameter_mm", scene.bone.kozenyCarmanDiameterMm},
                                   {"cortical_hu", scene.bone.corticalHu},
                                   {"soft_tissue_max_hu", scene.bone.softTissueMaxHu},
                                   {"soft_tissue_permeability_m2", scene.bone.softTissuePermeabilityM2}};
  } else {
    metrics["leakage_volume_ml"] = 0.0; // a pore-resolved CT has no soft tissue class: not assessed
    metrics["leakage_sites"] = json::array();
    metrics["leakage_assessed"] = false;
  }
  metrics["permeability_at_tip_m2"] = permeabilityAtTip;
  metrics["cannula_pressure_drop_pa"] = finalCannula;
  metrics["injection_pressure_pa"] = finalPressure + finalCannula;
  metrics["max_injection_pressure_pa"] = maxInjection;
  metrics["cement_volume_ml"] = filling.cementVolume() * 1e6;
  {
    json history = volumeHistory;
    history.push_back(volumeRecord());
    metrics["volume_history"] = history;
  }
  metrics["pressure_solves"] = st.solves;
  metrics["pressure_solver_iterations_mean"] = st.solves ? double(st.iterations) / double(st.solves) : 0.0;
  metrics["pressure_solver_worst_residual"] = st.worstResidual;
  metrics["pressure_solver_unconverged"] = st.unconverged;
  metrics["pressure_solve_wall_s"] = st.solveSeconds;
  metrics["pressure_assembly_wall_s"] = st.assemblySeconds;
  metrics["front_voxels"] = st.lastFrontVoxels;
  metrics["capillary_tension_n_per_m"] = scene.capillaryTensionNPerM;
  metrics["capillary_entry"] = scene.capillaryTensionNPerM > 0;
  metrics["capillary_solve_rounds"] = st.capillaryRounds;
  metrics["outlet_source_radius_mm"] = sourceRadius * 1e3;
  metrics["outlet_source_voxels"] = sourceVoxels;
  metrics["final_tip_pressure_pa"] = finalPressure;
  metrics["max_tip_pressure_pa"] = maxPressure;
  metrics["tip_pressure_baseline_pa"] = 0.0;
  metrics["mean_spreading_distance_mm"] = spread * 1e3;
  metrics["escaped_particles"] = 0;
  metrics["mass_balance_error"] = filling.injectedVolume() > 0
                                      ? (filling.injectedVolume() - filling.cementVolume()) / filling.injectedVolume()
                                      : 0.0;
  metrics["fluid_in_solid_fraction"] = 0.0; // closed voxels never take cement
  metrics["simulated_ct_hu_per_relative_density"] = o.huPerRelativeDensity;
  metrics["final_viscosity_pa_s"] = std::clamp(scene.curingFactor(filling.time()) * viscosity.at(filling.time()), lower, upper);

  InjectionRunResult result;
  result.particles = cementVoxelsToPolyData(filling, rho0);
  result.simulatedCt = simCt;
  if (writer.writing()) {
    // cement_labels.nrrd on the simulated CT's grid (a label map for 3D Slicer and the cement picture):
    // 1 where cement fills at least half a voxel's pores in bone, 2 where any cement is outside bone.
    auto labels = imaging::MaskType::New();
    labels->CopyInformation(simCt);
    labels->SetRegions(simCt->GetLargestPossibleRegion());
    labels->Allocate();
    std::uint8_t* l = labels->GetBufferPointer();
    for (std::size_t c = 0; c < m.count(); ++c) {
      const bool leaked = !softTissue.empty() && softTissue[c] && filling.fill()[c] > 0;
      l[c] = leaked ? 2 : filling.fill()[c] >= 0.5 ? 1 : 0;
    }
    imaging::writeMask(labels, (std::filesystem::path(o.outDir) / "cement_labels.nrrd").string());
  }
  writer.finish(filling.time(), result.particles, simCt, tipSeries, 0.0, metrics);
  result.metrics = metrics;
  return result;
}

} // namespace cementsph::scene::detail
