// One interface for every injection engine (docs/architecture.md, "Injection models").
//
// An engine (the SPH particles, the voxel-grid Darcy filling, the next one: a second phase, a fracture model)
// is an InjectionModel registered by name (InjectionModelRegistry; the built-in ones in
// src/InjectionModels.cpp, one line each). One driver, runInjection (InjectionRunner.h), owns everything the
// engines share: the scene's validation, the CT's orientation, the bone model and region of interest, the
// model choice, the time loop, snapshots, progress and stopping, the X-ray/CT series, the outlet-pressure
// series, and metrics.json, written once from the typed InjectionResult. An engine only sets itself up on the
// region, advances, and says what it holds.
//
// A step of the driver (InjectionDriver.cpp):
//   model.advance(dtMax)          one step of at most dtMax [s] (the next snapshot or the end of injection)
//   model.outlet()                the outlet pressure and the cannula's drop after it [Pa]
//   model.leakedVolumeM3()        with stop_at_first_leak: cement outside bone now
//   snapshot (model.cement(), model.cementDensity() -> simulated CT), progress (model.state())
// then model.finish(stopped) and model.report(result).
#pragma once

#include "cementsph/anatomy/VertebraAnatomy.h"
#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/scene/ModelSelection.h"
#include "cementsph/scene/PorousSolid.h"
#include "cementsph/scene/SceneConfig.h"
#include "cementsph/scene/SimulatedCT.h"
#include "cementsph/sph/Presets.h"

#include <nlohmann/json.hpp>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <array>
#include <cstdint>
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace cementsph::scene {

// One row of tip_pressure.csv: the outlet pressure and the cannula's drop at a time [s, Pa, Pa].
struct TipRecord {
  double time, tipPa, cannulaPa;
};

// Counts only a particle engine has (absent for an engine without particles, never faked as zeros).
struct ParticleCounts {
  std::size_t fluid = 0, fixed = 0, cannulaWall = 0, escaped = 0;
};

// Leakage: cement outside bone (only where the bone model knows what bone is: the continuum from HU).
struct LeakageSite {
  std::array<double, 3> positionMm{}; // volume-weighted centre, the CT's patient frame (LPS)
  double firstTimeS = 0, volumeMl = 0;
  std::string siteClass;              // "soft-tissue" (the HU rule), or an anatomical class
};

// The figures every engine reports, typed. metrics.json is toJson() of this (InjectionResult::metrics).
struct InjectionSummary {
  // The run.
  double volumeRequestedMl = 0, volumeInjectedMl = 0, cementVolumeMl = 0;
  double simulatedTimeS = 0, wallTimeS = 0;
  bool stoppedEarly = false, stoppedAtFirstLeak = false;
  std::size_t steps = 0;
  std::size_t cementPoints = 0;      // points of the cement output (particles, or voxels holding cement)
  std::optional<ParticleCounts> particles;
  // Which model ran and why ("model only what a scene needs").
  std::string engine;                // the registered name: "voxel-darcy", "incompressible", "equation-of-state"
  std::string model, modelReason, recommendedPressureModel, modelPreset, resistance, viscosityLaw;
  std::string boneModel, boneModelReason;
  nlohmann::json dimensionlessNumbers;
  bool pressureIsPhysical = false;   // gauge Pa; the weakly compressible pressure is the model's own
  bool ctResampled = false;          // an oblique CT was resampled onto an axis-aligned grid
  std::string ctOrientation;         // "axial", "reoriented" (axes flipped/swapped, exact) or "resampled" (oblique)
  // The region of interest on the (axis-aligned) CT grid.
  std::array<long, 3> roiStart{}, roiSize{};
  std::size_t solidVoxelsKept = 0, solidVoxelsTotal = 0, connectedPoreVoxels = 0;
  // Pressures [Pa].
  double finalTipPressurePa = 0, maxTipPressurePa = 0, tipPressureBaselinePa = 0;
  double cannulaPressureDropPa = 0, injectionPressurePa = 0, maxInjectionPressurePa = 0;
  // The cement.
  double meanSpreadingDistanceMm = 0;
  double massBalanceError = 0;       // (injected - held - left the region) / injected
  double fluidInSolidFraction = 0;   // of the cement, the share in solid voxels
  double finalViscosityPaS = 0;
  double huPerRelativeDensity = 0;   // k of the simulated CT [HU]
  bool leakageAssessed = false;
  double leakageVolumeMl = 0;
  std::vector<LeakageSite> leakageSites;
  nlohmann::json volumeHistory = nlohmann::json::array(); // {time_s, volume_injected_ml, cement_volume_ml}
  std::vector<std::string> warnings; // what a planning engineer must know (a shaft through the disc, ...)

  nlohmann::json toJson() const;
  // The inverse, for a summary that crossed a process boundary (MPI studies); throws std::invalid_argument
  // naming a missing or mistyped key.
  static InjectionSummary fromJson(const nlohmann::json& metrics);
};

// What a run returns: the typed summary, the engine's own figures (solver statistics, particle sums: keys
// that name their unit), and the images.
struct InjectionResult {
  InjectionSummary summary;
  nlohmann::json engineFigures = nlohmann::json::object();
  nlohmann::json metrics;                      // summary.toJson() merged with engineFigures (metrics.json)
  imaging::ImageType::Pointer simulatedCt;     // the (axis-aligned) CT's grid within the region of interest
  imaging::MaskType::Pointer cementLabels;     // on the region's grid (InjectionModel::cementLabels); null if none
  // The simulated CT and labels as the files hold them: on the INPUT CT's own grid (its size, origin, spacing,
  // direction; the input's HU outside the region), or the region's grid with InjectionRunOptions::cropToRegion.
  imaging::ImageType::Pointer simulatedCtFile;
  imaging::MaskType::Pointer cementLabelsFile;
  // The anatomy the run judged leakage by (InjectionModel::anatomyUsed: anatomy::TissueClass codes, 0 soft tissue,
  // 1 the target vertebra, ...) on the files' grid (anatomy_labels.nrrd); null when none, or no files are written.
  imaging::MaskType::Pointer anatomyLabelsFile;
  vtkSmartPointer<vtkPolyData> particles;      // the cement at the end (mm, the CT's frame, point arrays)
  std::vector<TipRecord> tipSeries;
};

// What a model sets itself up on: the region and the choices the driver made.
struct InjectionSetup {
  const imaging::ImageType* ct = nullptr;      // axis-aligned (AxisAlignedCT.h)
  const SceneConfig* scene = nullptr;
  const sph::ModelPreset* preset = nullptr;
  sph::ModelParameters model;                  // the preset's with the scene's overrides; h set
  const PorousSolid* solid = nullptr;
  const ModelChoice* choice = nullptr;
  bool continuum = false;                      // bone as a continuum from HU (BoneCalibration.h)
  const imaging::ImageType* labels = nullptr;  // the scene's label map on `ct`'s grid (labels_path), or null
};

class InjectionModel {
public:
  virtual ~InjectionModel() = default;
  // Sets the engine up; std::invalid_argument (one line naming the scene key) for a scene it cannot run.
  // Whether start() reads the solid's kept voxel centres (PorousSolid::keptPositions: 24 bytes a kept voxel and a
  // region-sized pass, made by the driver only for an engine that asks). The particle engines place fixed
  // particles there; an engine that reads the solid mask only says false.
  virtual bool readsKeptSolidCentres() const { return true; }
  virtual void start(const InjectionSetup& setup) = 0;
  virtual double time() const = 0;                        // simulated [s]
  // The run ends once time() >= T (1 - endSlack()): an engine that steps exactly to T (the voxel model) allows
  // round-off; one with steps of its own (the particles) runs until it has passed T, as it always did.
  virtual double endSlack() const { return 1e-12; }
  // One step of at most dtMax [s]; an engine with its own stability limit may take less. Throws
  // sph::SimulationError if the run goes unstable (naming where and why).
  virtual void advance(double dtMax) = 0;
  // The outlet (tip) pressure and the cannula's pressure drop now [Pa].
  virtual TipRecord outlet() const = 0;
  virtual double injectedVolumeM3() const = 0;
  virtual double cementVolumeM3() const = 0;
  // Cement outside bone now [m^3] (0 where the bone model has no such class).
  virtual double leakedVolumeM3() const { return 0.0; }
  // What the run holds, for the progress line ("674 fluid + 2100 fixed particles, 812 steps").
  virtual std::string state() const = 0;
  // Cement density per ROI voxel (PorousSolid::grid order) [kg/m^3], for the simulated CT.
  virtual std::vector<double> cementDensity() const = 0;
  // The same where it is not zero (SimulatedCT.h), for the result's images: an engine whose cement it knows by
  // voxel gives it without a region-sized array (the voxel engine); by default cementDensity()'s non-zero values.
  virtual SparseDensity cementDensityWhereNonZero() const { return nonZeroDensity(cementDensity()); }
  // The cement as points (mm, the CT's frame) with the engine's point arrays (particles_NNNN.vtp). A new
  // object on each call, not kept or changed by the engine afterwards: the driver writes it on another thread.
  // Before finish() an engine may give a reduced array set (the voxel engine's snapshots during the run: what the
  // last one, after finish(), holds for every point, docs/scene-figures.md); after finish(), every array.
  virtual vtkSmartPointer<vtkPolyData> cement() const = 0;
  // Snapshots as growth (scene snapshot_arrays "growth", issue 23): the cement that arrived since the previous
  // call (the first call: since the start) as points (mm, the CT's frame) with only arrays that never change
  // afterwards. The driver writes each as a piece and each snapshot as the union of the pieces so far
  // (particles_NNNN.pvtp; InjectionWriter::snapshotPiece merges old pieces), so a point is written about
  // log(snapshots) times a run, not once a snapshot. Null: the engine's cement moves (particles), and its
  // snapshots are whole (cement()).
  virtual vtkSmartPointer<vtkPolyData> cementArrivedSinceLastCall() { return nullptr; }
  // The state at the end: stopped, the driver stopped it early.
  virtual void finish(bool stopped) { (void)stopped; }
  // The engine's figures: fills what it knows of the summary (spreading, pressures' baseline, leakage, ...) and
  // its own keys in engineFigures.
  virtual void report(InjectionSummary& summary, nlohmann::json& engineFigures) const = 0;
  // The cement label map per ROI voxel (PorousSolid::grid order): 0 none, 1 cement in bone (at least half a
  // voxel's pores), 2 leaked (any cement outside bone); empty when the engine makes none. The driver writes it
  // as cement_labels.nrrd on the same grid as simulated_ct.nrrd.
  virtual std::vector<std::uint8_t> cementLabels() const { return {}; }
  // The tissue classes the engine judged leakage by (VertebraAnatomy.h: from the label map or the CT bone rule),
  // on the grid the classes were made on (the axis-aligned CT's, about the tip); null when it used none (the HU
  // rule, or an engine without anatomy). The driver writes it as anatomy_labels.nrrd.
  virtual const anatomy::Anatomy* anatomyUsed() const { return nullptr; }
  // The pressure column tip_pressure.csv subtracts (none: the model's pressure has no baseline yet).
  virtual std::optional<double> pressureBaselinePa() const { return 0.0; }
};

// Engines by name. A new engine is one folder (src/Models/<Name>/) and one line in src/InjectionModels.cpp;
// a test or a plug-in may add one at run time.
//
// Each engine declares the scene keys it reads besides commonSceneKeys() (those the driver reads for every
// engine). After the model is chosen, a key the user set (SceneConfig::explicitKeys) that neither list holds is
// a warning (sceneKeysNotRead): a particle-only key under voxel-darcy changes nothing, and the user must know.
class InjectionModelRegistry {
public:
  using Factory = std::function<std::unique_ptr<InjectionModel>()>;
  using SceneKeys = std::set<std::string>;
  struct Entry {
    Factory make;
    std::string description; // what metrics.json's "model" says: "incompressible-darcy-on-voxels", ...
    // The scene keys the engine reads besides the common ones; none: not declared (no key is reported unread).
    std::optional<SceneKeys> sceneKeys;
  };
  static InjectionModelRegistry& instance(); // with the built-in engines registered
  void add(const std::string& name, Factory factory, std::string description);
  // The same with the engine's scene keys; each must be a scene key (sceneKeyNames), else std::invalid_argument.
  void add(const std::string& name, Factory factory, std::string description, SceneKeys sceneKeys);
  bool has(const std::string& name) const;
  const Entry& at(const std::string& name) const; // std::invalid_argument listing the names
  std::vector<std::string> names() const;

private:
  std::map<std::string, Entry> entries_;
};

// An engine's pressure-solver figures under the keys both Darcy engines report: pressure_solves,
// pressure_solver_iterations_mean, pressure_solver_worst_residual, pressure_solver_unconverged,
// pressure_solve_wall_s.
void addPressureSolverFigures(nlohmann::json& engineFigures, std::size_t solves, std::size_t iterations,
                              double worstResidual, std::size_t unconverged, double solveSeconds);

// The built-in engines (src/InjectionModels.cpp).
void registerBuiltInInjectionModels(InjectionModelRegistry& registry);

// The scene keys the driver reads for every engine: the scene and model presets, the tip and cannula, the flow,
// the viscosity schedule, the region and the bone choice, the snapshots, the model choice (InjectionDriver.cpp).
const InjectionModelRegistry::SceneKeys& commonSceneKeys();
// The keys pressure_model "auto" reads to choose the model (ModelSelection.h): with "auto" they were not ignored.
const InjectionModelRegistry::SceneKeys& modelChoiceSceneKeys();

// One warning per key the user set (scene.explicitKeys) that the chosen engine `engine` does not read (neither
// common, nor the engine's, nor the choice's under "auto"), naming the key, the engine and why it was chosen,
// and which engines would read it. A key set to the value it has anyway (the scene preset's) changes nothing
// whatever the engine and is not reported: a recorded scene.json, which lists solid_mass_factor and
// fixed_particle_sums always, replays without noise. Nothing for an engine that declared no keys.
std::vector<std::string> sceneKeysNotRead(const SceneConfig& scene, const std::string& engine, const ModelChoice& choice,
                                          const InjectionModelRegistry& registry = InjectionModelRegistry::instance());

} // namespace cementsph::scene
