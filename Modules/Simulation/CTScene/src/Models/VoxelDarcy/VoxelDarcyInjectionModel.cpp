// The voxel-grid Darcy filling (VoxelDarcyFilling.h) as an injection engine (InjectionModel.h), registered as
// "voxel-darcy", the default for creeping flow. The cement is the filled voxels: its points
// (particles_NNNN.vtp) are one per voxel that holds cement (its centre, mm, the CT's frame) with fill_fraction,
// cement_volume_mm3, pressure_pa, darcy_velocity_m_per_s, viscosity_pa_s, porosity, permeability_m2,
// arrival_time_s, age_s, and as the particles' arrays velocity_m_per_s (the interstitial velocity q / phi) and
// density_kg_per_m3 (rho0: incompressible), all of them in the last snapshot and the run's result. The snapshots
// before the last (issue 23: a hundred a run) are, with snapshot_arrays "growth" (the default), the union of
// pieces holding the voxels that took cement with arrival_time_s (cementPiece; InjectionWriter::snapshotPiece
// merges them), and with "flow" every voxel's cement_volume_mm3, pressure_pa, darcy_velocity_m_per_s and
// viscosity (runningCementToPolyData). Also cement_labels.nrrd: a label map on the simulated CT's grid (1
// cement in bone, 2 leaked cement), which `cementsph inject` draws as cement_slices.png (leaks in red) and 3D
// Slicer opens as a segmentation.
//
// Leak physics: capillary entry at the pore throats (issue 20 item 2, issue 19 item 4). Decision and why.
//  * The problem. With an incompressible single-phase Darcy flow and the displaced marrow at one pressure, the
//    cement's shape, and so its leakage, cannot depend on a Newtonian viscosity: mu scales the pressure, not the
//    flow split. Clinically a more viscous (or later, more cured) cement leaks less. Three mechanisms can give
//    that: (a) marrow as a second, less viscous phase (0.05-0.4 Pa.s); (b) capillary entry at the throats;
//    (c) a fracture criterion at the cortex. (a) is negligible at the cement/marrow viscosity ratio of 10^2-10^4
//    (the marrow's pressure drop is that much smaller than the cement's: it cannot steer the front), and (c)
//    needs a cortex strength per voxel that a clinical CT does not give. (b) is the one whose size is within
//    reach: the entry pressure of a trabecular throat (10^1-10^3 Pa) is comparable to the viscous pressure at
//    the front of a slow injection, and it differs between fine bone and open paths (a vein, a fracture cleft,
//    a breach), so it can steer the front. It is what this engine models.
//  * The model. A front voxel j takes cement only while the cement beside it is above its entry pressure
//    p_e(j) = 2 sigma cos(theta) / r(j) (Young-Laplace for the cement as the non-wetting phase pushing the marrow
//    out of a throat of radius r; the front's Dirichlet condition p = 0 becomes p = p_e(j); a front voxel that
//    would drain is no-flux until the pressure rises: VoxelDarcyFilling's open/barred complementarity).
//    The throat radius: on a pore-resolved CT, the distance from the voxel to the solid (as before); on
//    continuum bone (a clinical CT), the capillary-bundle radius r = sqrt(8 k / phi): a bundle of straight tubes
//    of radius r and porosity phi has k = phi r^2 / 8 (Poiseuille per tube; Bear 1972, Dynamics of Fluids in
//    Porous Media, sec. 5.10; Dullien 1992, Porous Media, ch. 3), i.e. p_e = (2 / sqrt 8) sigma cos(theta)
//    sqrt(phi / k): Leverett's scaling (Leverett 1941, Trans. AIME 142:152) with J = 0.71 at entry (measured J at
//    entry in sands 0.2-0.5: the bundle is an upper bound of the throat, the lower bound of p_e). So fine
//    trabecular bone (k 1e-9..3e-8 m^2) has p_e ~ 70-400 Pa at sigma 0.025 N/m, an open path (soft tissue,
//    k = soft_tissue_permeability_m2 1e-7 m^2, phi 1) ~56 Pa, marrow fat (k ~5e-7 m^2) ~25 Pa.
//  * The parameters. sigma (capillary_tension_n_per_m): no measured PMMA-dough/marrow interfacial tension was
//    found; oil/water and triglyceride/water tensions are 0.02-0.03 N/m and MMA's surface tension 0.028 N/m, so
//    0.025 N/m (ModelSelection.h's kCementMarrowTensionNPerM) is an order-of-magnitude value, stated as such.
//    theta (contact_angle_deg, through the marrow): marrow (water and fat) wets bone better than the cement
//    dough; not measured either: 0 (cos 1) gives the largest entry pressure, an upper bound of the effect.
//  * Off by default (capillary_tension_n_per_m 0), and the `paper` preset unchanged: the mechanism rests on two
//    unmeasured parameters, and the default's single-phase oracles and figures stay exact. Its size at 0.025 N/m:
//    Ca 70-600 at 50-400 Pa.s on the vertebra phantom (entry pressures 25-100 Pa against kPa at the tip), which
//    moves the spreading by under 1 % but a small leak at the front's fringe by tens of percent (+37 % at 50 Pa.s,
//    +4 % at 400 Pa.s on the phantom with a vein, VALIDATION.md); leak figures are therefore given both ways in
//    the validation, and a planning user can switch it on per scene. metrics.json
//    says whether it ran, its capillary number Ca = (tip pressure - front entry pressure) / front entry pressure
//    (the viscous pressure across the cement over the capillary pressure: >> 1, viscosity dominates and the
//    front follows the mobility alone; ~ 1, the front prefers low-entry paths) and, off, the Ca it would have
//    at 0.025 N/m, so a user sees whether it could matter.
//  * What drives leakage here (leak_risk in metrics.json; measured on the vertebra phantom with a vein,
//    VALIDATION.md): with capillary entry, higher viscosity and curing raise Ca and cut the share of the cement
//    that takes the low-entry leak path; volume raises leakage (the front reaches the path).
//  * The flow rate (clinically, faster injection leaks more). Mu and Q enter an incompressible Darcy filling
//    only as their product in the pressure, so any mechanism keyed to the pressure (capillary entry, a vein
//    that opens above the venous pressure, a cortex that breaks above a stress) moves leakage the same way
//    with viscosity and with flow rate: it cannot give "falls with viscosity, rises with flow rate". Two
//    things separate them: time (curing: a slower injection's cement is older when the front reaches a vein)
//    and a rate-dependent law (shear-thinning). Measured on the vertebra phantom with a vein (capillary on,
//    3 ml, 0.0125-0.1 ml/s): curing (cmw1-37c, palacos-r-37c, palacos-r-25c) gave the clinical direction
//    only at the slowest rates and reversed above (Ca ~ Q exp(t_inj / tau): it falls with Q only while the
//    injection outlasts the curing time constant), so it is not the mechanism. Shear-thinning is: the
//    Darcy-scale shear rate is highest where the flux is (the open vein), and a faster injection thins the
//    cement there more, so a larger share takes the open path (Sochi 2010, J Polym Sci B 48:2437, reviews the
//    preferential flow of shear-thinning fluids into high-permeability paths; PMMA cements are shear-thinning:
//    Trivedi et al. 2023, Biomech Model Mechanobiol 22:1253, doi:10.1007/s10237-023-01715-4, and
//    arXiv:2312.11426). With a Carreau cement, single phase, leakage rises with Q from the Newtonian leak (Q ->
//    0) to the power law's (Q -> infinity; a power law is scale free and does not see Q) and does not depend on
//    mu0; with capillary entry the two effects compete and the shear-thinning wins above Ca ~ 500
//    (kShearThinningCrossoverCa; LeakFlowRateTest): a viscous shear-thinning cement then leaks more when faster
//    or larger and less when thicker, all four as clinically. A Newtonian cement keeps the reversed flow-rate
//    direction, and leak_risk's drivers say which case a run is in. Not modelled: cortex fracture and
//    pressure-opened veins (they see mu Q, see above).
#include "cementsph/scene/InjectionModel.h"

#include "cementsph/anatomy/LeakSites.h"
#include "cementsph/anatomy/VertebraAnatomy.h"

#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/BoneCalibration.h"
#include "cementsph/scene/ModelSelection.h"
#include "cementsph/scene/SimulatedCT.h"
#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/Simulation.h"
#include "cementsph/sph/TubeFlow.h"
#include "cementsph/voxeldarcy/VoxelDarcyFilling.h"

#include <itkImage.h>
#include <itkSignedMaurerDistanceMapImageFilter.h>
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkTypeInt32Array.h>
#include <vtkPointData.h>
#include <vtkPoints.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <vector>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace cementsph::scene {

using nlohmann::json;
using voxeldarcy::VoxelDarcyFilling;
using voxeldarcy::VoxelMedium;

namespace {

// The capillary number above which a shear-thinning (Carreau) cement's leakage rises with the flow rate despite
// the capillary steering (LeakFlowRateTest: on the vertebra phantom with a vein, n 0.3, lambda 1 s, it fell with
// the flow rate at Ca 70-190, had its minimum within Ca 180-470 and rose at Ca 530-1410).
constexpr double kShearThinningCrossoverCa = 500.0;

// The cannula's wall thickness [m] where the scene gives none: 11G regular wall, outer 3.048 mm against
// inner 2.388 mm (ISO 9626).
constexpr double kCannulaWallM = 0.33e-3;

// The edge of the cube the bone rule classifies about the tip [mm]: a lumbar body is 40-50 mm wide and its
// neighbours' end plates lie within 30 mm above and below; the rule needs the whole shell (VertebraAnatomy.h).
constexpr double kAnatomyCubeMm = 100.0;


// Capillary entry pressure of each pore voxel [Pa] on a pore-resolved CT: Young-Laplace for the cement entering
// a pore of the local radius r as the non-wetting phase, p_e = 2 sigma cos(theta) / r (`tension` is
// sigma cos(theta)). r is the distance from the voxel's centre to the solid's surface: the Euclidean distance
// to the nearest solid voxel centre (ITK's signed Maurer distance map, in mm) less half a voxel, at least half
// a voxel.
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

// sigma cos(theta) of the scene's capillary entry [N/m].
double tensionTimesCosine(const SceneConfig& scene) {
  return scene.capillaryTensionNPerM * std::cos(scene.contactAngleDeg * 3.14159265358979323846 / 180.0);
}

// Capillary entry pressure of each open voxel of a continuum medium [Pa]: the capillary-bundle throat
// r = sqrt(8 k / phi) (see the header), p_e = 2 sigma cos(theta) / r; `tension` is sigma cos(theta).
std::vector<float> continuumEntryPressure(const VoxelMedium& m, double tensionNPerM) {
  std::vector<float> entry(m.count(), 0.0f);
  for (std::size_t c = 0; c < m.count(); ++c)
    if (m.porosity[c] > 0) entry[c] = float(2.0 * tensionNPerM / std::sqrt(8.0 * m.permeabilityAt(c) / m.porosity[c]));
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

// The wet voxels in index order, kept between snapshots: the filling only appends to its wet list, so each
// snapshot sorts its newcomers and merges them in (linear), rather than sorting them all again (a snapshot's
// sort was 3 % of a 5 ml run in perf).
struct SortedWetVoxels {
  std::vector<std::size_t> sorted;
  std::size_t merged = 0; // how many of the filling's wet list `sorted` holds

  const std::vector<std::size_t>& update(const std::vector<std::size_t>& wet) {
    if (wet.size() < merged) sorted.clear(), merged = 0; // another filling: start again
    const std::size_t old = sorted.size();
    sorted.insert(sorted.end(), wet.begin() + std::ptrdiff_t(merged), wet.end());
    std::sort(sorted.begin() + std::ptrdiff_t(old), sorted.end());
    std::inplace_merge(sorted.begin(), sorted.begin() + std::ptrdiff_t(old), sorted.end());
    merged = wet.size();
    return sorted;
  }
};

// What a snapshot's making keeps from one snapshot to the next: the wet voxels in order and the scratch
// vectors of the gathered states (allocated once, not a hundred times a run).
struct SnapshotBuffers {
  SortedWetVoxels wetInOrder;
  std::vector<std::size_t> cells;
  std::vector<VoxelDarcyFilling::VoxelState> states;
  // The cement volume the last snapshot holds (the sum of its cement_volume_mm3, m^3) and the filling's state it
  // was taken at (simulated time, steps): the driver's volume record at a snapshot reads it instead of a second
  // pass over the cement (VoxelDarcyFilling::cementVolume: a tenth of the snapshots' cost, issue 23).
  double volumeM3 = 0;
  double volumeTime = -1;
  std::size_t volumeSteps = 0;
  void keepVolume(const VoxelDarcyFilling& f, double volumeMm3) {
    volumeM3 = volumeMm3 * 1e-9;
    volumeTime = f.time();
    volumeSteps = f.statistics().steps;
  }
  // Snapshots as growth: how much of the filling's wet list (in order of arrival) the pieces so far hold.
  std::size_t piecesHold = 0;
};

// One vertex cell per point (point i in cell i), with 32-bit offsets and connectivity: the files say Int32;
// VTK and ParaView read them as any VTP. ParaView's Threshold and point picking work per cell, so one cell per
// voxel (not one poly-vertex for all) even though it is 8 of a point's bytes.
vtkSmartPointer<vtkCellArray> vertexPerPoint(vtkIdType n) {
  if (n >= vtkIdType(std::numeric_limits<vtkTypeInt32>::max())) throw std::length_error(
      "cement snapshot: " + std::to_string(n) + " voxels hold cement, over the 2^31 a snapshot's vertices can number");
  auto offsets = vtkSmartPointer<vtkTypeInt32Array>::New(), connectivity = vtkSmartPointer<vtkTypeInt32Array>::New();
  offsets->SetNumberOfValues(n + 1);
  connectivity->SetNumberOfValues(n);
  vtkTypeInt32 *offsetOut = offsets->GetPointer(0), *connectivityOut = connectivity->GetPointer(0);
  for (vtkIdType i = 0; i <= n; ++i) offsetOut[i] = vtkTypeInt32(i);
  for (vtkIdType i = 0; i < n; ++i) connectivityOut[i] = vtkTypeInt32(i);
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  verts->SetData(offsets, connectivity);
  return verts;
}

// The points with a vertex cell each (vertexPerPoint).
vtkSmartPointer<vtkPolyData> vertexCloud(vtkPoints* points) {
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetVerts(vertexPerPoint(points->GetNumberOfPoints()));
  return poly;
}

template <class Array> vtkSmartPointer<Array> namedArray(const char* name, int components, vtkIdType n) {
  auto a = vtkSmartPointer<Array>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(n);
  return a;
}

void addFieldValue(vtkPolyData* poly, const char* name, double value) {
  auto a = vtkSmartPointer<vtkDoubleArray>::New();
  a->SetName(name);
  a->InsertNextValue(value);
  poly->GetFieldData()->AddArray(a);
}

// The cement during the run (every snapshot but the last; issue 23: a hundred of them a run, so each byte of a
// point is written a hundred times): one point per voxel holding cement, in order of arrival (the filling's own
// list: no lookup and no sort per voxel), with its vertex cell and the arrays that change while the cement
// flows: cement_volume_mm3, pressure_pa and darcy_velocity_m_per_s (single precision: 1e-7 of a value; the
// snapshot's volume sum is taken in double before rounding), and viscosity_pa_s as a point array where the
// voxels' viscosities differ (a shear-thinning cement), else one field-data value. The rest follows from the
// last snapshot, which holds every array for every voxel of every earlier one (find the voxel by its position):
// arrival_time_s, permeability_m2 and porosity never change once a voxel has cement, age_s is the snapshot's
// time minus arrival_time_s, fill_fraction is cement_volume_mm3 / (porosity x the voxel's volume),
// velocity_m_per_s is darcy_velocity_m_per_s / porosity and density_kg_per_m3 the rest density
// (incompressible), a field-data value in every snapshot. 40 bytes a point against the last one's 96.
vtkSmartPointer<vtkPolyData> runningCementToPolyData(const VoxelDarcyFilling& f, double restDensity,
                                                     SnapshotBuffers& buffers, bool viscosityPerVoxel) {
  const VoxelMedium& m = f.medium();
  const vtkIdType capacity = vtkIdType(f.wetVoxels().size());
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToFloat(); // mm to 1e-4 of a 40 mm region
  points->SetNumberOfPoints(capacity);
  auto volume = namedArray<vtkFloatArray>("cement_volume_mm3", 1, capacity);
  auto pressure = namedArray<vtkFloatArray>("pressure_pa", 1, capacity);
  auto velocity = namedArray<vtkFloatArray>("darcy_velocity_m_per_s", 3, capacity);
  auto viscosity = namedArray<vtkFloatArray>("viscosity_pa_s", 1, capacity);
  // Through the raw pointers: SetTuple's virtual call per value was a fifth of a snapshot's cost (perf).
  float *xyz = static_cast<vtkFloatArray*>(points->GetData())->GetPointer(0), *volumeOut = volume->GetPointer(0),
        *pressureOut = pressure->GetPointer(0), *velocityOut = velocity->GetPointer(0),
        *viscosityOut = viscosity->GetPointer(0);
  const double mm3PerPoreFill = m.voxelVolume() * 1e9;
  double volumeMm3 = 0, viscosityNow = 0;
  vtkIdType n = 0;
  f.forEachWetVoxel([&](std::size_t c, const VoxelDarcyFilling::VoxelState& s) {
    if (!(s.fill > 0)) return;
    const Eigen::Vector3d x = m.centre(c) * 1e3;
    for (int a = 0; a < 3; ++a) xyz[3 * n + a] = float(x[a]);
    const double mm3 = s.fill * m.porosity[c] * mm3PerPoreFill;
    volumeMm3 += mm3;
    volumeOut[n] = float(mm3);
    pressureOut[n] = float(s.pressure);
    for (int a = 0; a < 3; ++a) velocityOut[3 * n + a] = float(s.darcyVelocity[a]);
    viscosityNow = s.viscosity;
    viscosityOut[n] = float(s.viscosity);
    ++n;
  });
  // (shrinking keeps the allocation: no copy)
  points->SetNumberOfPoints(n);
  for (vtkDataArray* a : std::initializer_list<vtkDataArray*>{volume, pressure, velocity, viscosity}) a->SetNumberOfTuples(n);
  buffers.keepVolume(f, volumeMm3);
  auto poly = vertexCloud(points);
  for (vtkDataArray* a : std::initializer_list<vtkDataArray*>{volume, pressure, velocity}) poly->GetPointData()->AddArray(a);
  // The same layout in every snapshot of a run, so that ParaView colours the whole series alike: a point array
  // where the law gives each voxel its own viscosity, else the one value (every voxel's, VoxelDarcyFilling::
  // setViscosity; none before the cement arrives).
  if (viscosityPerVoxel) poly->GetPointData()->AddArray(viscosity);
  else if (n > 0) addFieldValue(poly, "viscosity_pa_s", viscosityNow);
  addFieldValue(poly, "density_kg_per_m3", restDensity);
  return poly;
}

// Snapshots as growth (InjectionModel::cementArrivedSinceLastCall, issue 23): the voxels that took cement
// since the last piece, in order of arrival, as points with the one array of theirs that never changes,
// arrival_time_s. 24 bytes a point with its vertex cell (12 position, 4 arrival, 8 the cell), written at most
// log2(snapshots) + 1 times a run (InjectionWriter::snapshotPiece merges the pieces).
vtkSmartPointer<vtkPolyData> cementPiece(const VoxelDarcyFilling& f, SnapshotBuffers& buffers) {
  const VoxelMedium& m = f.medium();
  // The wet list's newcomers: a voxel joins it as cement first enters it (VoxelDarcyFilling::wet, then its
  // fill rises above 0 in the same call) and never leaves it.
  const std::vector<std::size_t>& wet = f.wetVoxels();
  const std::vector<std::size_t> newcomers(wet.begin() + std::ptrdiff_t(buffers.piecesHold), wet.end());
  buffers.piecesHold = wet.size();
  const vtkIdType n = vtkIdType(newcomers.size());
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToFloat();
  points->SetNumberOfPoints(n);
  auto arrival = namedArray<vtkFloatArray>("arrival_time_s", 1, n);
  float *xyz = static_cast<vtkFloatArray*>(points->GetData())->GetPointer(0), *arrivalOut = arrival->GetPointer(0);
  const auto arrivalTime = f.arrivalTime();
  for (vtkIdType i = 0; i < n; ++i) {
    const std::size_t c = newcomers[std::size_t(i)];
    const Eigen::Vector3d x = m.centre(c) * 1e3;
    for (int a = 0; a < 3; ++a) xyz[3 * i + a] = float(x[a]);
    arrivalOut[i] = float(arrivalTime[c]);
  }
  auto poly = vertexCloud(points);
  poly->GetPointData()->AddArray(arrival);
  return poly;
}

// The cement at the end (the last snapshot and the run's result): one point per voxel holding cement, in
// voxel index order, with every array.
vtkSmartPointer<vtkPolyData> cementVoxelsToPolyData(const VoxelDarcyFilling& f, double restDensity,
                                                    SnapshotBuffers& buffers) {
  const VoxelMedium& m = f.medium();
  // The wet voxels, not the whole region (issue 23: a snapshot costs what the cement holds), in index order.
  // Each voxel's fields from one brick lookup (voxelState), not one per field.
  std::vector<std::size_t>& cells = buffers.cells;
  std::vector<VoxelDarcyFilling::VoxelState>& states = buffers.states;
  cells.clear();
  states.clear();
  for (std::size_t c : buffers.wetInOrder.update(f.wetVoxels())) {
    const VoxelDarcyFilling::VoxelState s = f.voxelState(c);
    if (!(s.fill > 0)) continue;
    cells.push_back(c);
    states.push_back(s);
  }
  const vtkIdType n = vtkIdType(cells.size());
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToFloat(); // mm to 1e-4 of a 40 mm region; half the bytes of doubles
  points->SetNumberOfPoints(n);
  // Single precision, but the fill and the volumes in double: they add up to the injected volume. Filled
  // through the raw pointers (SetTuple's virtual call per value was a fifth of a snapshot's cost, perf).
  auto fill = namedArray<vtkDoubleArray>("fill_fraction", 1, n), volume = namedArray<vtkDoubleArray>("cement_volume_mm3", 1, n);
  auto pressure = namedArray<vtkFloatArray>("pressure_pa", 1, n),
       velocity = namedArray<vtkFloatArray>("darcy_velocity_m_per_s", 3, n),
       viscosity = namedArray<vtkFloatArray>("viscosity_pa_s", 1, n), porosity = namedArray<vtkFloatArray>("porosity", 1, n),
       permeability = namedArray<vtkFloatArray>("permeability_m2", 1, n),
       arrival = namedArray<vtkFloatArray>("arrival_time_s", 1, n), age = namedArray<vtkFloatArray>("age_s", 1, n),
       speed = namedArray<vtkFloatArray>("velocity_m_per_s", 3, n),
       density = namedArray<vtkFloatArray>("density_kg_per_m3", 1, n);
  float* xyz = static_cast<vtkFloatArray*>(points->GetData())->GetPointer(0);
  double *fillOut = fill->GetPointer(0), *volumeOut = volume->GetPointer(0);
  float *pressureOut = pressure->GetPointer(0), *velocityOut = velocity->GetPointer(0),
        *viscosityOut = viscosity->GetPointer(0), *porosityOut = porosity->GetPointer(0),
        *permeabilityOut = permeability->GetPointer(0), *arrivalOut = arrival->GetPointer(0),
        *ageOut = age->GetPointer(0), *speedOut = speed->GetPointer(0), *densityOut = density->GetPointer(0);
  double volumeMm3 = 0;
  for (vtkIdType i = 0; i < n; ++i) {
    const std::size_t c = cells[std::size_t(i)];
    const VoxelDarcyFilling::VoxelState& s = states[std::size_t(i)];
    const Eigen::Vector3d x = m.centre(c) * 1e3;
    for (int a = 0; a < 3; ++a) xyz[3 * i + a] = float(x[a]);
    volumeOut[i] = s.fill * m.porosity[c] * m.voxelVolume() * 1e9;
    volumeMm3 += volumeOut[i];
    pressureOut[i] = float(s.pressure);
    const Eigen::Vector3d& q = s.darcyVelocity;
    for (int a = 0; a < 3; ++a) velocityOut[3 * i + a] = float(q[a]);
    viscosityOut[i] = float(s.viscosity);
    ageOut[i] = float(f.time() - s.arrival);
    const Eigen::Vector3d v = q / double(m.porosity[c]); // the cement's own (interstitial) velocity
    for (int a = 0; a < 3; ++a) speedOut[3 * i + a] = float(v[a]);
    densityOut[i] = float(restDensity);
    porosityOut[i] = m.porosity[c];
    fillOut[i] = s.fill;
    permeabilityOut[i] = float(m.permeabilityAt(c));
    arrivalOut[i] = float(s.arrival);
  }
  buffers.keepVolume(f, volumeMm3);
  auto poly = vertexCloud(points);
  for (vtkDataArray* a : std::initializer_list<vtkDataArray*>{fill, volume, pressure, velocity, viscosity, porosity,
                                                               permeability, arrival, age, speed, density})
    poly->GetPointData()->AddArray(a);
  addFieldValue(poly, "density_kg_per_m3", restDensity); // as in the snapshots before, which have no point array
  return poly;
}

// The voxel-grid Darcy filling as an injection engine.
class VoxelDarcyInjectionModel final : public InjectionModel {
public:
  bool readsKeptSolidCentres() const override { return false; } // the solid mask only
  void start(const InjectionSetup& in) override {
    const SceneConfig& scene = *in.scene;
    scene_ = &scene;
    solid_ = in.solid;
    continuum_ = in.continuum;
    rho0_ = in.model.restDensity;
    tip_ = *scene.tipMm * 1e-3;
    axis_ = scene.direction.normalized();
    innerDiameter_ = scene.cannulaInnerDiameterMm * 1e-3;
    cannulaLength_ = scene.cannulaLengthMm * 1e-3;
    flowRate_ = scene.flowRateM3PerS();
    T_ = scene.injectionDurationS();
    const PorousSolid& solid = *solid_;

    // The medium: the CT's pore voxels open, its solid voxels closed. A resolved pore voxel has the
    // permeability of the model preset's drag in open space, k0 = h^5 / (Cf d^3) (model-notes 3: the
    // paper's Eq. 9 resistance with no solid near), unless the scene gives pore_permeability_m2.
    const double d = scene.spacingM(), h = in.model.smoothingLength;
    poreK_ = scene.porePermeabilityM2.value_or(std::pow(h, 5) / (in.model.dragCoefficient * d * d * d));
    if (!(poreK_ >= 1e-18 && poreK_ <= 1e-3))
      throw std::invalid_argument("scene: the pore permeability k0 = h^5 / (Cf d^3) = " + std::to_string(poreK_) +
                                  " m^2 from particle_radius_mm and the preset is outside 1e-18 .. 1e-3 m^2 (give "
                                  "pore_permeability_m2, or a particle radius of a pore's scale)");
    VoxelMedium medium;
    medium.size = solid.grid.size;
    medium.origin = solid.grid.origin;
    medium.spacing = solid.grid.spacing;
    if (continuum_) {
      medium.porosity.assign(medium.count(), 1.0f);
      medium.permeability.assign(medium.count(), poreK_);
      // Which tissue each voxel is (Modules/Simulation/Anatomy): the target vertebra closed over its marrow,
      // disc, canal, vessel, ...; cement outside the target is leakage. The tip must be in the target.
      classifyTissues(*in.ct, in.labels, solid, scene);
      // Each voxel's porosity and permeability from its HU (BoneCalibration.h). Marrow fat inside the target
      // (below soft_tissue_max_hu, enclosed by cortex) is bone at its most porous, not an open leak path.
      const auto start = in.ct->GetLargestPossibleRegion().GetIndex();
      for (std::size_t c = 0; c < medium.count(); ++c) {
        const auto v = medium.ijk(c);
        imaging::ImageType::IndexType idx;
        for (unsigned a = 0; a < 3; ++a) idx[a] = start[a] + solid.roiStart[a] + v[a];
        double hu = in.ct->GetPixel(idx);
        if (!leak_[c] && scene.bone.tissue(hu) == BoneCalibration::Tissue::SoftTissue) hu = scene.bone.softTissueMaxHu;
        medium.porosity[c] = float(scene.bone.porosity(hu));
        medium.permeability[c] = scene.bone.permeability(hu);
      }
    } else {
      // Pore-resolved: porosity 1 in pore voxels, 0 in solid ones, and one permeability (no array of it), in one
      // branch-free pass over the region.
      medium.uniformPermeability = poreK_;
      medium.porosity.resize(medium.count());
      const std::uint8_t* solidAt = solid.solid.data();
      float* phi = medium.porosity.data();
      for (std::size_t c = 0; c < medium.count(); ++c) phi[c] = solidAt[c] ? 0.0f : 1.0f;
    }
    // Capillary entry (the header): sigma cos(theta). On continuum bone the entry pressures at unit tension are
    // kept whether or not it is on, for the capillary number it would have (metrics.json); taken before the
    // shaft closes its voxels, so that the tract a withdrawn cannula opens has its own bone's entry pressure.
    const double tension = tensionTimesCosine(scene);
    if (continuum_) unitEntry_ = continuumEntryPressure(medium, 1.0);
    closeShaft(medium);
    sourceRadius_ = std::max(0.5 * innerDiameter_, 0.5 * solid.grid.spacing.minCoeff());
    filling_ = std::make_unique<VoxelDarcyFilling>(std::move(medium));
    filling_->setSource(tip_, sourceRadius_);
    if (tension > 0) {
      if (continuum_) {
        std::vector<float> entry(unitEntry_.size());
        for (std::size_t c = 0; c < entry.size(); ++c) entry[c] = float(tension * double(unitEntry_[c]));
        filling_->setEntryPressure(std::move(entry));
      } else {
        filling_->setEntryPressure(capillaryEntryPressure(solid, tension));
      }
    }
    viscosity_ = scene.viscositySchedule();
    // The cement's law: Newtonian (the schedule) or shear-thinning, times the curing factor.
    shearThinning_ = scene.viscosityLaw != "newtonian";
    law_ = sph::makeRheology(scene.viscosityLaw, scene.rheology);
    lower_ = scene.rheology.minimumViscosityPaS;
    upper_ = scene.rheology.maximumViscosityPaS;
    // The second tip's start (never, with one tip).
    secondTipStart_ = scene.hasSecondTip() ? scene.secondTipStartS() : 2 * T_;
    atSecondTip_ = !scene.hasSecondTip();
  }

  double time() const override { return filling_->time(); }

  void advance(double dtMax) override {
    const SceneConfig& scene = *scene_;
    const double t = filling_->time();
    const double factor = scene.curingFactor(t);
    const double mu = std::clamp(factor * viscosity_->at(t), lower_, upper_);
    if (shearThinning_) {
      const auto law = law_;
      const double lower = lower_, upper = upper_;
      filling_->setShearRateViscosity(
          [law, factor, lower, upper](double g) { return std::clamp(factor * law->unbounded(g), lower, upper); },
          law->flowIndex(), 3);
    } else {
      filling_->setViscosity(mu);
    }
    // At most 1 % of the injection per step: progress every 1 % and a tip-pressure curve with 100 points.
    // The driver's dtMax (the next snapshot, the end) only stops this call: a step it cuts short goes on at
    // the next call with the same inflows (VoxelDarcyFilling::step's stopAfter), so snapshots add no
    // pressure solves (at 10 ml, 1 s snapshots had made 257 solves of the 169 the run needs).
    double stepMax = 0.01 * T_;
    if (!atSecondTip_ && secondTipStart_ - t > 1e-9 * T_) stepMax = std::min(stepMax, secondTipStart_ - t);
    try {
      filling_->step(flowRate_, stepMax, dtMax);
    } catch (const voxeldarcy::FillingError& e) {
      throw sph::SimulationError(e.what()); // a failed run, as an unstable particle run
    }
    if (!atSecondTip_ && filling_->time() >= secondTipStart_ * (1 - 1e-12)) {
      // The cannula is withdrawn: its tract opens, and the outlet is the second tip from now on.
      filling_->openVoxels(tractVoxels_, tractPorosity_, tractPermeability_);
      try {
        filling_->setSource(tip_ - withdrawal_ * axis_, sourceRadius_);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("scene: the second tip, second_tip_withdrawal_mm back along the axis: " +
                                    std::string(e.what()));
      }
      atSecondTip_ = true;
    }
    outlet_ = {filling_->time(), filling_->sourcePressure(), cannulaDrop(factor, mu)};
  }

  TipRecord outlet() const override { return outlet_; }
  double injectedVolumeM3() const override { return filling_->injectedVolume(); }
  // The last snapshot's sum where the filling has not moved since (the driver asks at each snapshot), else a pass.
  double cementVolumeM3() const override {
    if (snapshots_.volumeTime == filling_->time() && snapshots_.volumeSteps == filling_->statistics().steps)
      return snapshots_.volumeM3;
    return filling_->cementVolume();
  }
  double leakedVolumeM3() const override { return leak_.empty() ? 0.0 : leakage(*filling_, leak_, nullptr); }

  std::string state() const override {
    return std::to_string(filling_->statistics().lastUnknowns) + " filled voxels, " +
           std::to_string(filling_->statistics().steps) + " steps";
  }

  // kg/m^3 of cement per ROI voxel (its filled pore fraction at rho0).
  // Zero but where cement reached: the sparse density below spread over the region.
  std::vector<double> cementDensity() const override {
    std::vector<double> rho(filling_->medium().count(), 0.0);
    for (const auto& [c, r] : cementDensityWhereNonZero()) rho[c] = r;
    return rho;
  }

  // The voxels cement reached (VoxelDarcyFilling::wetVoxels, a superset of those with fill > 0), in index order,
  // where their density is not zero: a pass over the cement, not a brick lookup per region voxel (issue 23).
  SparseDensity cementDensityWhereNonZero() const override {
    SparseDensity rho;
    for (std::size_t c : wetInOrder()) {
      const double r = filling_->fill()[c] * filling_->medium().porosity[c] * rho0_;
      if (r != 0) rho.emplace_back(c, r);
    }
    return rho;
  }

  // The voxels cement reached, in index order (kept between calls: the snapshots' buffer).
  const std::vector<std::size_t>& wetInOrder() const { return snapshots_.wetInOrder.update(filling_->wetVoxels()); }

  // The snapshots during the run hold the reduced set, the last one (after finish) and the result every array.
  vtkSmartPointer<vtkPolyData> cement() const override {
    return finished_ ? cementVoxelsToPolyData(*filling_, rho0_, snapshots_)
                     : runningCementToPolyData(*filling_, rho0_, snapshots_, shearThinning_);
  }
  vtkSmartPointer<vtkPolyData> cementArrivedSinceLastCall() override { return cementPiece(*filling_, snapshots_); }
  void finish(bool) override { finished_ = true; }

  void report(InjectionSummary& s, json& e) const override {
    const SceneConfig& scene = *scene_;
    const VoxelDarcyFilling& filling = *filling_;
    const VoxelMedium& m = filling.medium();
    double spread = 0, held = 0;
    std::size_t cementVoxels = 0;
    // The voxels cement reached, in index order (the sums as a pass over the region adds them), not the region.
    for (std::size_t c : wetInOrder()) {
      const double v = filling.fill()[c] * m.porosity[c];
      if (v <= 0) continue;
      ++cementVoxels;
      spread += v * (m.centre(c) - tip_).norm();
      held += v;
    }
    if (held > 0) spread /= held;
    const std::size_t sourceVoxels = filling.sourceVoxels().size();
    double porosityAtTip = 0, permeabilityAtTip = 0;
    for (std::size_t c : filling.sourceVoxels()) {
      porosityAtTip += m.porosity[c] / double(sourceVoxels);
      permeabilityAtTip += m.permeabilityAt(c) / double(sourceVoxels);
    }
    const auto& st = filling.statistics();
    s.steps = st.steps;
    s.solidVoxelsKept = solid_->solidVoxels; // every solid voxel of the region is a closed voxel
    s.resistance = continuum_                   ? "continuum permeability from HU (Kozeny-Carman)"
                   : scene.porePermeabilityM2 ? "pore-permeability (scene)"
                                              : "pore-permeability (preset drag k0)";
    s.viscosityLaw = scene.viscosityLaw;
    s.pressureIsPhysical = true;
    s.meanSpreadingDistanceMm = spread * 1e3;
    s.massBalanceError = filling.injectedVolume() > 0
                             ? (filling.injectedVolume() - filling.cementVolume()) / filling.injectedVolume()
                             : 0.0;
    s.fluidInSolidFraction = 0.0; // closed voxels never take cement
    s.finalViscosityPaS = std::clamp(scene.curingFactor(filling.time()) * viscosity_->at(filling.time()), lower_, upper_);
    s.leakageAssessed = continuum_; // a pore-resolved CT has no soft tissue class: not assessed
    if (continuum_ && anatomy_) {
      // Leak sites by anatomical class: disc, canal, venous, other bone, cortex breach (LeakSites.h).
      std::vector<double> fill(m.count()), arrival(m.count()), porosity(m.count());
      for (std::size_t c = 0; c < m.count(); ++c) {
        fill[c] = filling.fill()[c];
        arrival[c] = std::isfinite(filling.arrivalTime()[c]) ? filling.arrivalTime()[c] : -1.0;
        porosity[c] = m.porosity[c];
      }
      const anatomy::LeakReport report = anatomy::classifyLeaks(*anatomy_, fill, arrival, porosity);
      s.leakageVolumeMl = report.leakedMl;
      for (const anatomy::LeakSite& site : report.sites)
        s.leakageSites.push_back({site.positionMm, site.firstTimeS, site.volumeMl, site.kind});
      e["anatomy"] = anatomy_->toJson();
      e["leakage_by_class"] = report.toJson();
    } else if (continuum_) {
      json sites;
      s.leakageVolumeMl = leakage(filling, leak_, &sites) * 1e6;
      for (const json& site : sites)
        s.leakageSites.push_back({site.at("position_mm").get<std::array<double, 3>>(), site.at("first_time_s").get<double>(),
                                  site.at("volume_ml").get<double>(), "soft-tissue"});
    }
    s.warnings.insert(s.warnings.end(), shaftWarnings_.begin(), shaftWarnings_.end());
    if (continuum_) {
      e["leak_rule"] = leakRule_;
      e["bone_calibration"] = {{"marrow_hu", scene.bone.marrowHu},
                               {"bone_tissue_hu", scene.bone.boneTissueHu},
                               {"kozeny_carman_diameter_mm", scene.bone.kozenyCarmanDiameterMm},
                               {"cortical_hu", scene.bone.corticalHu},
                               {"soft_tissue_max_hu", scene.bone.softTissueMaxHu},
                               {"soft_tissue_permeability_m2", scene.bone.softTissuePermeabilityM2}};
    }

    if (scene.hasSecondTip()) {
      const Eigen::Vector3d second = scene.secondTipMm();
      e["second_tip_mm"] = {second.x(), second.y(), second.z()};
      e["second_tip_start_s"] = secondTipStart_;
      e["second_tip_volume_ml"] = scene.secondTipVolumeMl;
    }
    e["cement_voxels"] = cementVoxels;
    e["cannula_shaft_voxels_closed"] = shaftVoxels_;
    double lo = std::numeric_limits<double>::infinity(), hi = 0;
    for (std::size_t c : wetInOrder())
      if (filling.filled(c)) {
        lo = std::min(lo, filling.viscosity()[c]);
        hi = std::max(hi, filling.viscosity()[c]);
      }
    e["apparent_viscosity_min_pa_s"] = std::isfinite(lo) ? lo : 0.0;
    e["apparent_viscosity_max_pa_s"] = hi;
    e["curing_factor_at_end"] = scene.curingFactor(filling.time());
    e["curing_factor_at_start"] = scene.curingFactor(0.0);
    e["curing_model"] = scene.curing().kind();
    e["pore_permeability_m2"] = poreK_;
    e["porosity_at_tip"] = porosityAtTip;
    e["permeability_at_tip_m2"] = permeabilityAtTip;
    addPressureSolverFigures(e, st.solves, st.iterations, st.worstResidual, st.unconverged, st.solveSeconds);
    e["pressure_assembly_wall_s"] = st.assemblySeconds;
    e["front_voxels"] = st.lastFrontVoxels;
    e["capillary_tension_n_per_m"] = scene.capillaryTensionNPerM;
    e["capillary_entry"] = !filling.entryPressure().empty();
    e["capillary_solve_rounds"] = st.capillaryRounds;
    reportLeakRisk(s, e);
    e["outlet_source_radius_mm"] = sourceRadius_ * 1e3;
    e["outlet_source_voxels"] = sourceVoxels;
  }

  // 1 where cement fills at least half a voxel's pores in bone, 2 where any cement is outside bone.
  const anatomy::Anatomy* anatomyUsed() const override { return usedAnatomy_ ? &*usedAnatomy_ : nullptr; }

  std::vector<std::uint8_t> cementLabels() const override {
    const VoxelMedium& m = filling_->medium();
    std::vector<std::uint8_t> l(m.count(), 0); // 0 where no cement came (fill 0)
    for (std::size_t c : filling_->wetVoxels()) {
      const bool leaked = !leak_.empty() && leak_[c] && filling_->fill()[c] > 0;
      l[c] = leaked ? 2 : filling_->fill()[c] >= 0.5 ? 1 : 0;
    }
    return l;
  }

private:
  // The capillary entry's state and the leak-risk figure (metrics.json "capillary" and "leak_risk"), from the
  // last step's front: where the cement was flowing when the injection ended.
  //   capillary number Ca = (tip pressure - p_e) / p_e, p_e the inflow-weighted mean entry pressure of the front
  //     voxels in the target bone: the viscous pressure across the cement over the capillary pressure that
  //     steers it (off: with sigma 0.025 N/m, theta 0, on continuum bone, what it would be);
  //   leak_flux_fraction: the share of the last step's inflow going into voxels outside the target (cement that
  //     is leaking at the end), and leaked_volume_fraction: leakage / injected volume.
  void reportLeakRisk(const InjectionSummary& s, json& e) const {
    const SceneConfig& scene = *scene_;
    const VoxelDarcyFilling& filling = *filling_;
    const bool on = !filling.entryPressure().empty();
    const double assumedTension = on ? tensionTimesCosine(scene) : kCementMarrowTensionNPerM;
    double total = 0, out = 0, boneFlow = 0, boneEntry = 0;
    for (const auto& [c, q] : filling.frontInflow()) {
      total += q;
      const bool outside = !leak_.empty() && leak_[c];
      if (outside) out += q;
      double pe = on ? double(filling.entryPressure()[c]) : unitEntry_.empty() ? -1.0 : assumedTension * unitEntry_[c];
      if (!outside && pe >= 0) {
        boneFlow += q;
        boneEntry += q * pe;
      }
    }
    json cap;
    cap["on"] = on;
    cap["tension_n_per_m"] = scene.capillaryTensionNPerM;
    cap["contact_angle_deg"] = scene.contactAngleDeg;
    cap["throat_radius_rule"] = continuum_ ? "capillary bundle r = sqrt(8 k / phi) (Leverett scaling)"
                                          : "distance from the pore voxel to the solid";
    std::optional<double> ca;
    if (boneFlow > 0 && boneEntry > 0) {
      const double pe = boneEntry / boneFlow;
      // The viscous pressure: the tip's, less the entry pressure it works against when on.
      const double viscous = filling.sourcePressure() - (on ? pe : 0.0);
      ca = viscous / pe;
      cap["front_entry_pressure_pa"] = pe;
      cap["viscous_pressure_pa"] = viscous;
      cap["capillary_number"] = *ca;
    }
    std::ostringstream why;
    why.precision(3);
    // No verdict from Ca alone: the front's shift toward low-entry paths is small (1 / Ca of the viscous pressure),
    // but a leak at the front's fringe is small too (on the vertebra phantom with a vein, Ca 79 raised a 0.038 ml
    // leak by 37 %, Ca 620 by 4 %).
    if (on) {
      why << "on: the scene sets capillary_tension_n_per_m " << scene.capillaryTensionNPerM
          << " N/m, contact_angle_deg " << scene.contactAngleDeg;
      if (ca) why << "; Ca " << *ca << ": the entry pressure steers the front toward low-entry paths as 1 / Ca";
    } else {
      why << "off (capillary_tension_n_per_m 0, the default: its parameters are not measured, "
             "VoxelDarcyInjectionModel.cpp)";
      if (ca)
        why << "; at sigma " << kCementMarrowTensionNPerM << " N/m it would have Ca " << *ca
            << " (the steering falls as 1 / Ca; set capillary_tension_n_per_m to see what it does to the leak)";
    }
    cap["reason"] = why.str();
    e["capillary"] = cap;

    json risk;
    risk["assessed"] = !leak_.empty();
    risk["leak_flux_fraction"] = total > 0 ? out / total : 0.0;
    risk["leaked_volume_fraction"] =
        filling.injectedVolume() > 0 ? s.leakageVolumeMl * 1e-6 / filling.injectedVolume() : 0.0;
    if (ca) risk["capillary_number"] = *ca;
    // Which way each clinical driver moves the leak in this model (measured on the vertebra phantom with a vein,
    // VALIDATION.md; LeakFlowRateTest, CapillaryLeakTest); Ca is proportional to viscosity x flow rate / tension.
    // The flow rate acts two ways: through Ca (capillary entry: a faster injection steers less toward low-entry
    // paths, less leakage) and through shear-thinning (Carreau: a faster injection thins the cement more in the
    // high-flux open paths, more leakage). Above the crossover (Ca ~ 500 measured on the phantom, n 0.3,
    // lambda 1 s) the second wins.
    const bool carreau = scene.viscosityLaw == "carreau";
    const char* none = "none: single-phase Darcy, the flow split does not depend on it";
    const char* thinning = "higher raises leakage (a shear-thinning cement thins most in the open, high-flux leak "
                           "paths and a faster injection thins it more), as clinically";
    std::string flowRate;
    if (!on) {
      flowRate = carreau ? thinning
                         : scene.viscosityLaw == "power-law"
                               ? "none: a power law is scale free, the flow split does not depend on the flow rate"
                               : none;
    } else if (carreau && ca && *ca >= kShearThinningCrossoverCa) {
      flowRate = std::string(thinning) + "; here it outweighs the capillary steering (Ca above ~" +
                 std::to_string(int(kShearThinningCrossoverCa)) + ")";
    } else {
      flowRate = carreau ? "two opposite effects: shear-thinning raises leakage with the flow rate, the capillary "
                           "steering (Ca below ~500) cuts it and wins at low Ca; a more viscous cement gives the "
                           "clinical direction"
                         : "higher cuts leakage here (raises Ca): opposite to the clinical finding; a shear-thinning "
                           "(viscosity_law carreau) viscous cement (Ca above ~500) gives the clinical direction";
      // A curing cement: Ca goes with the viscosity the cement has reached times the flow rate, and a slower
      // injection lets it thicken first, so the two can cancel (VALIDATION.md's curing rows are non-monotone in Q).
      if (!carreau && scene.curing().kind() != "none")
        flowRate += "; with this curing cement a slower injection lets it thicken first (Ca ~ viscosity reached x "
                    "flow rate), so the direction can reverse";
    }
    risk["drivers"] = {
        {"viscosity", on ? "higher cuts leakage (raises Ca), as clinically" : none},
        {"curing", on ? "later or faster curing cuts leakage (raises the viscosity, so Ca), as clinically" : none},
        {"flow_rate", flowRate},
        {"volume", "larger raises leakage (the front reaches the leak paths), as clinically"}};
    e["leak_risk"] = risk;
  }

  // The tissue classes of the region (leak_ and anatomy_). The bone rule runs on a cube of kAnatomyCubeMm about
  // the tip (a vertebra is larger than the region of interest, and the rule needs its whole shell), and the
  // region takes its voxels' classes. Where no walled vertebra is found around the tip (a block of bone, a
  // synthetic half-space), the HU rule stays: cement in voxels below soft_tissue_max_hu is leakage.
  void classifyTissues(const imaging::ImageType& ct, const imaging::ImageType* labelMap, const PorousSolid& solid,
                       const SceneConfig& scene) {
    const std::size_t n = solid.grid.count();
    leak_.assign(n, 0);
    const auto region = ct.GetLargestPossibleRegion();
    // Region voxel c as CT index (relative to the CT region's start), x fastest.
    auto roiIndex = [&](std::size_t c) {
      const long nx = solid.grid.size[0], ny = solid.grid.size[1], cc = long(c);
      return std::array<long, 3>{solid.roiStart[0] + cc % nx, solid.roiStart[1] + (cc / nx) % ny,
                                 solid.roiStart[2] + cc / (nx * ny)};
    };
    const Eigen::Vector3d tipMm = *scene.tipMm;
    // The cube, clipped to the CT (voxel indices relative to the region's start).
    std::array<long, 3> lo{}, count{};
    for (unsigned a = 0; a < 3; ++a) {
      const double s = ct.GetSpacing()[a];
      const long centre = long(std::lround((tipMm[int(a)] - ct.GetOrigin()[a]) / s)) - long(region.GetIndex()[a]);
      const long half = long(std::ceil(0.5 * kAnatomyCubeMm / s));
      lo[a] = std::max(0L, centre - half);
      count[a] = std::min(long(region.GetSize()[a]), centre + half + 1) - lo[a];
    }
    anatomy::Grid grid;
    std::vector<float> hu;
    std::vector<std::int32_t> labels;
    hu.reserve(std::size_t(count[0] * count[1] * count[2]));
    for (unsigned a = 0; a < 3; ++a) {
      grid.size[a] = int(count[a]);
      grid.spacingMm[a] = ct.GetSpacing()[a];
      grid.originMm[a] = ct.GetOrigin()[a] + double(region.GetIndex()[a] + lo[a]) * ct.GetSpacing()[a];
    }
    for (long k = 0; k < count[2]; ++k)
      for (long j = 0; j < count[1]; ++j)
        for (long i = 0; i < count[0]; ++i)
        {
          imaging::ImageType::IndexType idx;
          idx[0] = region.GetIndex()[0] + lo[0] + i;
          idx[1] = region.GetIndex()[1] + lo[1] + j;
          idx[2] = region.GetIndex()[2] + lo[2] + k;
          hu.push_back(ct.GetPixel(idx));
          if (labelMap) labels.push_back(std::int32_t(std::lround(labelMap->GetPixel(idx))));
        }
    anatomy::AnatomyOptions options;
    options.softTissueMaxHu = scene.bone.softTissueMaxHu;
    options.corticalHu = scene.bone.corticalHu;
    const std::array<double, 3> tip{tipMm.x(), tipMm.y(), tipMm.z()};
    anatomy::Anatomy cube;
    if (labelMap) {
      anatomy::LabelTable table = anatomy::LabelTable::totalSegmentator();
      if (!scene.labelTable.is_null()) {
        try {
          table = anatomy::LabelTable::fromJson(scene.labelTable);
        } catch (const std::exception& e) {
          throw std::invalid_argument(std::string("scene: label_table: ") + e.what());
        }
      }
      cube = anatomy::classifyAnatomyFromLabels(hu.data(), labels.data(), grid, tip, table, options);
    } else {
      cube = anatomy::classifyAnatomyFromCT(hu.data(), grid, tip, options);
    }
    if (!cube.targetFound && !labelMap) {
      leakRule_ = "hu: cement below soft_tissue_max_hu is leakage (no vertebra walled by cortex around the tip: " +
                  cube.description + ")";
      for (std::size_t c = 0; c < n; ++c) {
        const auto v = roiIndex(c);
        imaging::ImageType::IndexType idx;
        for (unsigned a = 0; a < 3; ++a) idx[a] = region.GetIndex()[a] + v[a];
        const double h = ct.GetPixel(idx);
        leak_[c] = scene.bone.tissue(h) == BoneCalibration::Tissue::SoftTissue;
      }
      return;
    }
    anatomy::requireTipInVertebra(cube, hu.data(), tip, scene.allowTipOutsideBone);
    // In a vertebra the cannula's direction decides which voxels its shaft closes and whether the shaft crosses
    // disc, canal or a vessel: the default [0, 0, 1] (a shaft from straight below, through the endplate) would
    // be silently wrong there. The synthetic phantoms (foam, no vertebra) keep the default by design.
    if (!scene.directionGiven()) {
      const std::string found = cube.rule == "labels" ? "by the label map" : "walled by cortex in the CT";
      throw std::invalid_argument("scene: key 'direction' is missing: the tip is in a vertebra (found " + found +
                                  "), where the default [0, 0, 1] (a shaft from straight below) would be silently "
                                  "wrong; give the cannula's direction from the entry point toward the tip in the "
                                  "CT's frame (LPS), e.g. \"direction\": [0, -1, 0] from behind, or --set "
                                  "direction=[x,y,z]");
    }
    // The region's classes from the cube (the same grid, offset by the region's start).
    anatomy::Anatomy roi;
    roi.rule = cube.rule;
    roi.description = cube.description;
    roi.targetFound = true;
    roi.targetCentroidMm = cube.targetCentroidMm;
    for (unsigned a = 0; a < 3; ++a) {
      roi.grid.size[a] = solid.grid.size[int(a)];
      roi.grid.spacingMm[a] = solid.grid.spacing[int(a)] * 1e3;
      roi.grid.originMm[a] = solid.grid.origin[int(a)] * 1e3;
    }
    roi.classes.assign(n, std::uint8_t(anatomy::TissueClass::OtherSoftTissue));
    for (std::size_t c = 0; c < n; ++c) {
      const auto v = roiIndex(c);
      const long i = v[0] - lo[0], j = v[1] - lo[1], k = v[2] - lo[2];
      if (i >= 0 && j >= 0 && k >= 0 && i < count[0] && j < count[1] && k < count[2])
        roi.classes[c] = cube.classes[std::size_t(i + count[0] * (j + count[1] * k))];
      leak_[c] = roi.at(c) != anatomy::TissueClass::TargetVertebra;
    }
    leakRule_ = "anatomy (" + cube.rule + "): cement outside the target vertebra is leakage; " + cube.description;
    // The cannula's shaft, a cannula length behind the tip: through the disc, the canal or a vessel it is a
    // plan to look at again (a transpedicular shaft crosses the pedicle's cortex, which is expected).
    const Eigen::Vector3d axis = scene.direction.normalized();
    const double step = 0.25 * cube.grid.spacingMm[0];
    for (anatomy::TissueClass bad :
         {anatomy::TissueClass::Disc, anatomy::TissueClass::Canal, anatomy::TissueClass::Vessel}) {
      double first = -1, last = -1;
      for (double behind = step; behind <= scene.cannulaLengthMm; behind += step) {
        const Eigen::Vector3d p = tipMm - behind * axis;
        if (cube.atPoint({p.x(), p.y(), p.z()}) == bad) {
          if (first < 0) first = behind;
          last = behind;
        }
      }
      if (first >= 0) {
        std::ostringstream w;
        w.precision(3);
        w << "the cannula's shaft crosses " << anatomy::tissueWords(bad) << " " << first << " to " << last
          << " mm behind the tip (direction " << axis.x() << ", " << axis.y() << ", " << axis.z()
          << "): check the trajectory";
        shaftWarnings_.push_back(w.str());
      }
    }
    anatomy_ = std::move(roi);
    usedAnatomy_ = std::move(cube); // the whole cube, for anatomy_labels.nrrd
  }

  // The cannula's shaft behind the outlet is closed (cement cannot flow back into or along it): voxels more
  // than half a voxel behind the outlet plane, so that the voxel holding the tip stays open wherever the tip
  // falls within it. With a second tip, the stretch of the shaft between the two outlets opens when the
  // cannula is withdrawn: those voxels, with their own porosity and permeability.
  void closeShaft(VoxelMedium& medium) {
    if (!scene_->cannulaWall) return;
    withdrawal_ = scene_->hasSecondTip() ? *scene_->secondTipWithdrawalMm * 1e-3 : 0.0;
    const double outer = 0.5 * innerDiameter_ + kCannulaWallM;
    const double behind = 0.5 * solid_->grid.spacing.maxCoeff();
    // Only the voxels in the box about the shaft's cylinder (its axis from a cannula length to half a voxel
    // behind the tip, widened by its outer radius and a voxel) can be in it: visited in voxel order, as a pass
    // over the whole region would, but in time of the shaft, not the region (issue 23: 7 % of a whole-scan run).
    const Eigen::Vector3d from = tip_ - cannulaLength_ * axis_, to = tip_ - behind * axis_;
    int lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      auto index = [&](double x) {
        return int(std::clamp((x - medium.origin[d]) / medium.spacing[d], -2.0, double(medium.size[d]) + 1.0));
      };
      lo[d] = std::max(0, index(std::min(from[d], to[d]) - outer) - 1);
      hi[d] = std::min(medium.size[d] - 1, index(std::max(from[d], to[d]) + outer) + 1);
    }
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const std::size_t c = medium.index(i, j, k);
          const Eigen::Vector3d r = medium.centre(c) - tip_;
          const double s = r.dot(axis_);
          if (s < -behind && s >= -cannulaLength_ && (r - s * axis_).norm() <= outer && medium.porosity[c] > 0) {
            if (withdrawal_ > 0 && s + withdrawal_ >= -behind) {
              tractVoxels_.push_back(c);
              tractPorosity_.push_back(medium.porosity[c]);
              tractPermeability_.push_back(medium.permeabilityAt(c));
            }
            medium.porosity[c] = 0.0f;
            ++shaftVoxels_;
          }
        }
  }

  // The cannula's pressure drop [Pa]: Hagen-Poiseuille (Eq. 13) or, shear-thinning, the tube integral
  // (Rabinowitsch-Mooney), once per curing factor (the general integral takes ~20 ms).
  double cannulaDrop(double factor, double mu) {
    const SceneConfig& scene = *scene_;
    if (!shearThinning_) return sph::hagenPoiseuillePressureDrop(mu, cannulaLength_, flowRate_, innerDiameter_);
    if (factor != cachedFactor_) {
      if (scene.viscosityLaw == "power-law") {
        cachedCannula_ = sph::powerLawTubePressureDrop(factor * scene.rheology.consistencyPaSn, scene.rheology.flowIndex,
                                                       cannulaLength_, flowRate_, innerDiameter_);
      } else {
        sph::RheologyParameters p = scene.rheology;
        p.zeroShearViscosityPaS *= factor;
        p.infiniteShearViscosityPaS *= factor;
        cachedCannula_ = sph::tubePressureDrop(*sph::makeRheology(scene.viscosityLaw, p), cannulaLength_, flowRate_,
                                               innerDiameter_);
      }
      cachedFactor_ = factor;
    }
    return cachedCannula_;
  }

  const SceneConfig* scene_ = nullptr;
  const PorousSolid* solid_ = nullptr;
  bool continuum_ = false, shearThinning_ = false, atSecondTip_ = true;
  double rho0_ = 0, innerDiameter_ = 0, cannulaLength_ = 0, flowRate_ = 0, T_ = 0, poreK_ = 0, sourceRadius_ = 0;
  double lower_ = 0, upper_ = 0, secondTipStart_ = 0, withdrawal_ = 0;
  double cachedFactor_ = -1, cachedCannula_ = 0;
  Eigen::Vector3d tip_, axis_;
  std::vector<std::uint8_t> leak_; // continuum: voxels outside the target bone, where cement is leakage
  std::vector<float> unitEntry_;   // continuum: each voxel's entry pressure at sigma cos(theta) = 1 N/m [Pa]
  std::optional<anatomy::Anatomy> anatomy_; // continuum: the tissue classes on the region's grid
  std::optional<anatomy::Anatomy> usedAnatomy_; // the same classes on the cube the rule ran on (anatomyUsed)
  std::string leakRule_;
  std::vector<std::string> shaftWarnings_;
  std::size_t shaftVoxels_ = 0;
  std::vector<std::size_t> tractVoxels_;
  std::vector<float> tractPorosity_;
  std::vector<double> tractPermeability_;
  std::unique_ptr<VoxelDarcyFilling> filling_;
  bool finished_ = false;             // finish() called: cement() gives every array
  mutable SnapshotBuffers snapshots_; // kept between snapshots (cement() is const to the driver)
  std::optional<sph::ViscositySchedule> viscosity_;
  std::shared_ptr<const sph::Rheology> law_;
  TipRecord outlet_{0, 0, 0};
};

} // namespace

std::unique_ptr<InjectionModel> makeVoxelDarcyInjectionModel() { return std::make_unique<VoxelDarcyInjectionModel>(); }

// The scene keys this engine reads besides the driver's (InjectionModel.h): the particle spacing and the preset's
// drag through the default pore permeability k0 = h^5 / (Cf d^3), the capillary entry, the cement's law and
// curing, the continuum's calibration and anatomy (labels, leaks, a tip outside bone), the second tip.
InjectionModelRegistry::SceneKeys voxelDarcySceneKeys() {
  return {"particle_radius_mm", "drag_coefficient", "pore_permeability_m2", "capillary_tension_n_per_m",
          "contact_angle_deg",
          "viscosity_law", "consistency_pa_s_n", "flow_index", "zero_shear_viscosity_pa_s",
          "infinite_shear_viscosity_pa_s", "carreau_time_constant_s", "viscosity_min_pa_s", "viscosity_max_pa_s",
          "mixing_to_injection_s", "curing_table", "cement", "curing_model", "curing_time_s", "cured_viscosity_pa_s",
          "curing_reference_time_s", "marrow_hu", "bone_tissue_hu", "kozeny_carman_diameter_mm",
          "soft_tissue_max_hu", "soft_tissue_permeability_m2", "stop_at_first_leak", "allow_tip_outside_bone",
          "labels_path", "label_table", "second_tip_withdrawal_mm", "second_tip_volume_ml", "snapshot_arrays"};
}

} // namespace cementsph::scene
