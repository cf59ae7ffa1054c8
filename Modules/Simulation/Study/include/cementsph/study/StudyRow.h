// One run of a study and what it measured: the inject runner's speed figures (wall time, steps, real-time
// factor, particle counts) and the cement its simulated CT shows, with the errors against the reference
// (CementErrors). A run that failed (the engine went unstable) keeps its spec and the reason.
#pragma once

#include "cementsph/study/CementErrors.h"
#include "cementsph/study/StudyPlan.h"

#include <cstddef>
#include <optional>
#include <string>

namespace cementsph::study {

struct StudyRow {
  StudyRunSpec spec;
  std::string failure;              // empty: the run finished
  bool ok() const { return failure.empty(); }
  int rank = 0;                     // the MPI rank that ran the injection (0 in a serial study)

  // From the inject runner (metrics.json keys in brackets).
  double wallTimeS = 0;             // [wall_time_s], porous-solid set-up included
  double realTimeFactor = 0;        // [real_time_factor] simulated s per wall s
  double simulatedTimeS = 0;        // [simulated_time_s]
  std::size_t steps = 0;            // [steps]
  std::size_t fluidParticles = 0;   // [fluid_particles] present at the end
  std::size_t fixedParticles = 0;   // [fixed_particles] solid voxels kept + cannula wall
  std::size_t escapedParticles = 0; // [escaped_particles]
  double volumeInjectedMl = 0;      // [volume_injected_ml]
  double expectedParticles = 0;     // requested volume / (2r)^3: the volume-exact emitter's count
  double particleSpreadingMm = 0;   // [mean_spreading_distance_mm]: mean particle distance from the tip
  double maxTipPressurePa = 0;      // [max_tip_pressure_pa]
  double finalTipPressurePa = 0;    // [final_tip_pressure_pa]: the outlet pressure at the end of injection
  double fluidInSolidFraction = 0;  // [fluid_in_solid_fraction]

  // The simulated CT's cement, segmented as `compare` does (AnalysedCement), and its errors.
  bool cementFound = false;
  double cementVolumeMl = 0;
  double cementSpreadingMm = 0;     // mean distance of cement voxel centres from the tip
  CementErrors errors;              // against the reference; empty without one (viscosity sweep)
  double analysisTimeS = 0;         // segmentation, isosurface and distances
};

} // namespace cementsph::study
