// How big an injection run is, estimated from the scene before anything is allocated: particle counts,
// a lower bound on the steps, the memory, and the work (particle-steps). A scene whose particle radius is a
// micrometre asks for 10^20 particles; one whose max_displacement_over_h is 1e-9 for 10^12 steps. Both used
// to start, climb past 9 GB or run for ever; checkRunSize refuses them with one line naming the key, and
// notes a long run before it starts.
#pragma once

#include "cementsph/scene/SceneConfig.h"

#include <cstdint>
#include <optional>
#include <string>

namespace cementsph::scene {

struct RunEstimate {
  double fluidParticles = 0;    // volume_ml / d^3
  double wallParticles = 0;     // cannula wall rings and filled bore at spacing d/2 (CannulaEmitter)
  double solidParticlesMax = 0; // every CT voxel of the ROI cube (an upper bound: only solid ones are kept)
  double steps = 0;             // lower bound: one particle emitted per step at most, and the overdamped move limit
  double memoryBytes = 0;
  double particleSteps = 0;     // steps x the mean number of fluid particles in flight (half the total)
  // Which scene key makes the run this large (for the message).
  std::string drivingKey;
  double estimatedWallSeconds() const;
  // The voxel-grid Darcy filling (the creeping-flow default, ModelSelection.h), when the scene runs it: the
  // ROI's voxels (an upper bound), the cement's voxels (volume over voxel volume, a lower bound), its memory
  // and time. The particle figures above are still checked: a scene whose particle keys are absurd is bad
  // input whichever model runs (the particle radius also sets the pore permeability k0 = h^5 / (Cf d^3)).
  bool voxelDarcy = false;
  double voxels = 0, cementVoxels = 0, voxelMemoryBytes = 0, voxelSeconds = 0;
};

// voxelVolumeMm3: the CT's voxel volume (0 when not known yet: the solid is then left out).
RunEstimate estimateRun(const SceneConfig& scene, double voxelVolumeMm3 = 0);

// Limits: memory above half the machine's RAM (above all of it even with allowLarge), or an estimated wall
// time over kMaxEstimatedSeconds, throws std::invalid_argument with one line (what, how much, which key to
// change, and --allow-large where that helps). Returns a note for runs estimated over kNoteEstimatedSeconds
// (empty otherwise), of the model that runs. The time is the work over a rate measured on a slow machine
// (RunEstimate.cpp).
constexpr double kMaxEstimatedSeconds = 3 * 3600.0;
constexpr double kNoteEstimatedSeconds = 120.0;
std::string checkRunSize(const RunEstimate& estimate, bool allowLarge);

// Physical memory of this machine in bytes.
double physicalMemoryBytes();

} // namespace cementsph::scene
