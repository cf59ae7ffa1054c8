#include "cementsph/scene/RunEstimate.h"

#include "cementsph/scene/ModelSelection.h"
#include "cementsph/sph/Presets.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cementsph::scene {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Bytes per particle, rounded up from the engine's arrays: a fluid particle's state (about 20 doubles) and
// its neighbour list (about 60 neighbours within 2h + skin); a fixed particle's position, mass and bin.
constexpr double kBytesPerFluidParticle = 1024, kBytesPerFixedParticle = 256;
// The tabulated solid field keeps about 4 floats per node where cement goes (about 4 times its volume).
constexpr double kBytesPerFieldNode = 32, kFieldVolumeOverCementVolume = 4;
// Measured: the paper's 1 ml scene on Data/foam-phantom (`cementsph inject ... --threads 1`, while a build
// kept the other core busy): 816 steps x 674/2 fluid particles in 7.55 s = 3.6e4 per second. A slow,
// loaded machine on purpose: the estimate should not promise less time than a run takes.
constexpr double kParticleStepsPerSecond = 3.6e4;
// The voxel-grid Darcy filling: the medium built over the ROI (porosity, permeability), the filling's state in
// bricks that follow the cement and its front (VoxelDarcyFilling.h: fill, pressure, viscosity, arrival, face
// fluxes, numbering; all of the ROI once the cement reaches most of it), the ROI's solid mask, kept solid centres
// and the simulated CT, and the run's other buffers peak at about 200 bytes per ROI voxel (RunEstimateMemoryTest
// measures the peak resident memory of a 512 000-voxel run: 206 bytes per voxel on 2026-12-03). Its work: about max(100, 3 n^(1/3)) pressure solves for
// n cement voxels (139 for the 5 ml phantom scene, 47 600 voxels), each ~100 CG iterations over half of them
// on average; measured 3.5e8 voxel-iterations in 2.64 s (1.3e8 per second, one core with the other busy).
constexpr double kBytesPerVoxel = 200, kVoxelIterationsPerSecond = 1.3e8;
// InjectionRunner's overdamped move limit when the scene does not set max_displacement_over_h.
constexpr double kDefaultMaxDisplacementOverH = 0.25;

std::string number(double x) {
  std::ostringstream s;
  s.precision(3);
  s << x;
  return s.str();
}

std::string duration(double seconds) {
  if (seconds < 120) return number(seconds) + " s";
  if (seconds < 7200) return number(seconds / 60) + " min";
  if (seconds < 3 * 86400) return number(seconds / 3600) + " h";
  return number(seconds / 86400) + " days";
}

} // namespace

double physicalMemoryBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && pageSize > 0 ? double(pages) * double(pageSize) : 8e9;
}

double RunEstimate::estimatedWallSeconds() const { return particleSteps / kParticleStepsPerSecond; }

RunEstimate estimateRun(const SceneConfig& scene, double voxelVolumeMm3) {
  RunEstimate e;
  const double d = 2.0 * scene.particleRadiusMm; // mm
  const double s = 0.5 * d;                      // wall spacing (CannulaEmitter: wallSpacingFraction 0.5)
  e.fluidParticles = scene.volumeMl * 1e3 / (d * d * d);
  if (scene.cannulaWall) {
    const double rings = scene.cannulaLengthMm / s + 1;
    const double wall = rings * 2.0 * kPi * (scene.cannulaInnerDiameterMm + 2 * s) / s; // two layers
    const double bore = kPi * std::pow(0.5 * scene.cannulaInnerDiameterMm + 0.25 * s, 2) / (s * s) * rings;
    e.wallParticles = wall + bore;
  }
  if (voxelVolumeMm3 > 0) e.solidParticlesMax = std::pow(scene.roiSizeMm, 3) / voxelVolumeMm3;

  const sph::ModelPreset preset = sph::modelPreset(scene.modelPreset);
  const double h = preset.hOverD * d; // mm
  // Emission puts at most one particle in per step, so there are at least as many steps as particles.
  e.steps = e.fluidParticles;
  e.drivingKey = "particle_radius_mm";
  const sph::Integrator integrator = scene.integrator ? sph::parseIntegrator(*scene.integrator) : preset.model.integrator;
  if (integrator == sph::Integrator::Overdamped) {
    // The fastest cement leaves the bore at Q / A; a step moves it at most max_displacement_over_h h.
    const double exitSpeedMmPerS =
        scene.flowRateMlPerS * 1e3 / (0.25 * kPi * scene.cannulaInnerDiameterMm * scene.cannulaInnerDiameterMm);
    const double moveSteps = scene.injectionDurationS() * exitSpeedMmPerS /
                             (scene.maxDisplacementOverH.value_or(kDefaultMaxDisplacementOverH) * h);
    if (moveSteps > e.steps) {
      e.steps = moveSteps;
      if (scene.maxDisplacementOverH) e.drivingKey = "max_displacement_over_h";
    }
  }
  e.particleSteps = e.steps * 0.5 * e.fluidParticles;
  e.memoryBytes = e.fluidParticles * kBytesPerFluidParticle +
                  (e.wallParticles + e.solidParticlesMax) * kBytesPerFixedParticle;
  if (scene.fixedSumMethod() == sph::FixedSumMethod::Tabulated) {
    const double node = scene.fixedFieldSpacingOverH.value_or(preset.model.fixedFieldSpacing) * h;
    e.memoryBytes += kFieldVolumeOverCementVolume * scene.volumeMl * 1e3 / (node * node * node) * kBytesPerFieldNode;
  }
  const double cs = scene.soundSpeedMPerS.value_or(preset.model.soundSpeed);
  e.voxelDarcy = chooseModel(scene, preset.model.restDensity, cs, 1.0).pressureModel == "voxel-darcy";
  if (e.voxelDarcy && voxelVolumeMm3 > 0) {
    e.voxels = std::pow(scene.roiSizeMm, 3) / voxelVolumeMm3;
    e.cementVoxels = scene.volumeMl * 1e3 / voxelVolumeMm3;
    const double solves = std::max(100.0, 3.0 * std::cbrt(e.cementVoxels));
    e.voxelSeconds = solves * 100.0 * 0.5 * e.cementVoxels / kVoxelIterationsPerSecond;
    e.voxelMemoryBytes = e.voxels * kBytesPerVoxel;
  }
  return e;
}

std::string checkRunSize(const RunEstimate& e, bool allowLarge) {
  const double ram = physicalMemoryBytes();
  const std::string counts = number(e.fluidParticles) + " cement, " + number(e.wallParticles) + " cannula" +
                             (e.solidParticlesMax > 0 ? ", up to " + number(e.solidParticlesMax) + " solid" : "") +
                             " particles";
  if (e.memoryBytes > (allowLarge ? 1.0 : 0.5) * ram)
    throw std::invalid_argument("scene: this run needs about " + number(e.memoryBytes / 1e9) + " GB (" + counts +
                                ") and the machine has " + number(ram / 1e9) + " GB: raise particle_radius_mm" +
                                (allowLarge ? "" : " (or pass --allow-large to use up to all of the memory)"));
  // The particle model's time limits a voxel-grid run only through a key whose value is absurd for any
  // model (a move limit of 1e-9 h is a mistake, not a plan); the volume or radius of a voxel run does not
  // make it long in particle steps.
  const bool particleTimeApplies = !e.voxelDarcy || e.drivingKey == "max_displacement_over_h";
  if (particleTimeApplies && e.estimatedWallSeconds() > kMaxEstimatedSeconds && !allowLarge)
    throw std::invalid_argument("scene: key '" + e.drivingKey + "' makes this run about " + number(e.steps) +
                                " steps over " + counts + ", some " + duration(e.estimatedWallSeconds()) +
                                ": raise it, or pass --allow-large to run it anyway");
  if (e.voxelMemoryBytes > (allowLarge ? 1.0 : 0.5) * ram)
    throw std::invalid_argument("scene: this run needs about " + number(e.voxelMemoryBytes / 1e9) + " GB for " +
                                number(e.voxels) + " voxels of the region and the machine has " + number(ram / 1e9) +
                                " GB: lower roi_size_mm" + (allowLarge ? "" : " (or pass --allow-large to use up to all of the memory)"));
  if (e.voxelDarcy) {
    if (e.voxelSeconds > kNoteEstimatedSeconds)
      return "note: a large run, about " + number(e.cementVoxels) + " cement voxels in a region of " +
             number(e.voxels) + ": expect " + duration(e.voxelSeconds) + " or more";
    return {};
  }
  if (e.estimatedWallSeconds() > kNoteEstimatedSeconds)
    return "note: a large run, about " + number(e.steps) + " steps over " + counts + ": expect " +
           duration(e.estimatedWallSeconds()) + " or more";
  return {};
}

} // namespace cementsph::scene
