#include "cementsph/scene/RunEstimate.h"

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
  if (e.estimatedWallSeconds() > kMaxEstimatedSeconds && !allowLarge)
    throw std::invalid_argument("scene: key '" + e.drivingKey + "' makes this run about " + number(e.steps) +
                                " steps over " + counts + ", some " + duration(e.estimatedWallSeconds()) +
                                ": raise it, or pass --allow-large to run it anyway");
  if (e.estimatedWallSeconds() > kNoteEstimatedSeconds)
    return "note: a large run, about " + number(e.steps) + " steps over " + counts + ": expect " +
           duration(e.estimatedWallSeconds()) + " or more";
  return {};
}

} // namespace cementsph::scene
