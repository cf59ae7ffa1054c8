// The inject runner: a CT and a scene in, an injection simulation to the end of injection, files out. One
// driver (src/InjectionDriver.cpp) for every engine (InjectionModel.h: the particles, src/Models/Particles; the
// voxel-grid Darcy filling, src/Models/VoxelDarcy).
//
// Assembly (as Testing/Core/SPH/InjectionScene.h, with the CT's porous solid): model preset (+ the scene's
// overrides), d = 2r, h = (h/d) d; the porous solid of the ROI (PorousSolid.h) as fixed particles of mass
// rho0 V_voxel; the cannula emitter (volume-exact, optional wall of length cannula_length_mm, clipped to the
// ROI); the viscosity schedule applied each step; the pressure model chosen from the scene's dimensionless
// numbers (ModelSelection.h; scene key pressure_model). The outlet pressure: with the equation of state the
// paper's six-point ring (TipPressureProbe, model pressure); incompressible, the mean pressure of the cement
// the outlet's source feeds (gauge Pa). The simulation box is the ROI: particles leaving it are removed and
// counted (possible leakage).
//
// Files in outDir (each written atomically, temporary name then rename):
//   metrics.json        the run's figures (see docs/scene-figures.md)
//   tip_pressure.csv    time_s, pressure_pa (outlet), pressure_minus_baseline_pa (equation of state: baseline
//                       the mean of the first 0.5 s; incompressible: none, the pressure itself),
//                       cannula_pressure_drop_pa (Hagen-Poiseuille), injection_pressure_pa (outlet + cannula)
//   particles_NNNN.vtp  every snapshot_interval_s and at the end; positions in mm (the CT's frame), point
//                       arrays velocity_m_per_s, density_kg_per_m3, pressure_pa, age_s, viscosity_pa_s,
//                       volume_fraction (the incompressible model's kernel sum), front (1 at the cement front).
//                       voxel-darcy (docs/scene-figures.md): the last is particles_NNNN.vtp with every array;
//                       the earlier ones, with snapshot_arrays "growth" (the default), particles_NNNN.pvtp: the
//                       union of pieces (particles_piece_NNNN.vtp, merged four at a time into
//                       particles_piece_FFFF-LLLL.vtp), the voxels that took cement by then with arrival_time_s;
//                       with "flow", .vtp files of every such voxel's cement_volume_mm3, pressure_pa and
//                       darcy_velocity_m_per_s then
//   particles.pvd       the ParaView series of the snapshots
//   simulated_ct.nrrd   the CT's grid within the ROI: HU_sim = HU_pre + k rho_fluid / rho0, rho_fluid the Eq. 2
//                       fluid density at the voxel centre with h = 2r (ParticleVoxeliser), k = 3000 HU
//   scene.json          the scene as run (all values resolved)
// With the scene key simulated_ct_snapshots (SimulatedCT.h), also:
//   simulated_ct_start.nrrd  the simulated CT at t = 0 (no cement: the CT's ROI), an X-ray sequence's background
//   simulated_ct_NNNN.nrrd   at each particles_NNNN.vtp (same numbering; the last equals simulated_ct.nrrd)
//   sequence.json            {"frames": [{"index", "time_s", "simulated_ct", "particles" (null at t = 0)}, ...]}
//   metrics.json then holds simulated_ct_snapshots (frames written) and simulated_ct_snapshots_wall_s (their cost)
#pragma once

#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/scene/InjectionModel.h"
#include "cementsph/scene/SceneConfig.h"
#include "cementsph/sph/Particles.h"

#include <nlohmann/json.hpp>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <functional>
#include <string>

namespace cementsph::scene {

struct InjectionRunOptions {
  std::string outDir;               // empty: write no files
  double huPerRelativeDensity = 3000.0; // k of the simulated CT [HU]
  bool progress = false;            // a progress line on stderr (with an ETA when stderr is a terminal)
  // simulated_ct.nrrd and cement_labels.nrrd on the region of interest's grid instead of the input CT's own
  // (smaller files; the input-grid files subtract voxel by voxel from the input, in 3D Slicer or numpy).
  bool cropToRegion = false;
  // Called now and then with the fraction of injection time done (0..1); return false to stop the run.
  std::function<bool(double)> onProgress;
  // Stop once the engine has started (every check a run makes before its first step: scene, tip outside the CT
  // or in solid, pore space, the engine's own start checks) and return an empty result; no file is written. A
  // study checks all its runs this way before the first one starts, so bad input is one line at once.
  bool checkOnly = false;
  // With simulated_ct_snapshots and files written: called with each frame of the CT series as it is made (t = 0
  // without cement first, then each snapshot's; the last the final state), the frame on the region's grid as
  // simulated_ct_NNNN.nrrd holds it, valid during the call only. A caller that projects the frames (inject's
  // X-ray sequence) takes them here instead of reading the files back, and no frame is held after its call.
  std::function<void(double timeS, const imaging::ImageType& frame)> onCtFrame;
};

// The typed result (InjectionModel.h): summary, the engine's figures, metrics.json as written, the images.
using InjectionRunResult = InjectionResult;

// Throws std::invalid_argument for a bad scene or CT/tip combination, sph::SimulationError if the run goes
// unstable, std::runtime_error for output failures.
InjectionRunResult runInjection(const imaging::ImageType* ct, const SceneConfig& scene, const InjectionRunOptions& options);

// Fluid particles as points in mm with velocity_m_per_s, density_kg_per_m3, pressure_pa, age_s.
vtkSmartPointer<vtkPolyData> particlesToPolyData(const sph::FluidParticles& fluid, double time);

} // namespace cementsph::scene
