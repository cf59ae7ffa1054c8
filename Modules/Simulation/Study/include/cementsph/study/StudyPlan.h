// What a study runs. The paper's particle-size study (Basafa et al. 2013, "Simulations", Fig. 6: particle
// radii 1.00, 0.75, 0.57, 0.50 and 0.45 mm, error against computation time) made into a speed-against-error
// report over integrators too, and the viscosity sweep of its Fig. 8 (mean spreading distance against
// viscosity at one particle size).
//
// Size study: every radius with every integrator (the engine's names: overdamped, central-difference,
// explicit; "paper" is read as central-difference), the scene's model preset and every other key as they
// are. The reference is either the finest run, i.e. the smallest radius with the most faithful integrator in
// the list (central-difference, the paper's Eq. 8, before explicit, before overdamped, which drops inertia),
// or a post-operative CT given by the caller. The reference run goes first, so that every row written after
// it already carries its errors.
// Viscosity sweep: each viscosity at the scene's radius and integrator (constant viscosity only).
#pragma once

#include "cementsph/scene/SceneConfig.h"

#include <string>
#include <vector>

namespace cementsph::study {

struct StudyRunSpec {
  enum class Sweep { ParticleSize, Viscosity };
  Sweep sweep = Sweep::ParticleSize;
  double particleRadiusMm = 0.57;
  std::string integrator;   // canonical engine name
  double viscosityPaS = 100.0;
  bool reference = false;   // the size study's reference run

  // The base scene with this run's radius, integrator and viscosity.
  scene::SceneConfig scene(const scene::SceneConfig& base) const;
  // A folder-safe name: "central-difference_r0.45mm", "viscosity_200pa_s".
  std::string name() const;
};

struct StudyPlan {
  scene::SceneConfig baseScene;                       // validated scene (tip included)
  bool sizeStudy = true;
  std::vector<double> radiiMm{1.00, 0.75, 0.57, 0.50, 0.45};
  std::vector<std::string> integrators{"overdamped", "central-difference"};
  std::vector<double> viscositiesPaS;                 // empty: no viscosity sweep
  bool referenceIsCt = false;                         // the reference is a post-operative CT, not a run

  // Throws std::invalid_argument, one line naming the option: no run at all, a radius or viscosity not
  // finite and > 0, a duplicate, an unknown integrator, a viscosity sweep over a scene whose viscosity is not
  // constant (viscosity_rate_pa_per_s or viscosity_table). Integrator names are made canonical.
  void validate();

  // The size study's runs: the reference first (unless referenceIsCt), then every other pair, integrators in
  // the order given and radii in the order given.
  std::vector<StudyRunSpec> sizeRuns() const;
  std::vector<StudyRunSpec> viscosityRuns() const;
};

// Rank of an integrator by faithfulness to the paper's model (higher is more faithful): central-difference 2,
// explicit 1, overdamped 0. Throws std::invalid_argument for an unknown name.
int integratorFaithfulness(const std::string& integrator);

} // namespace cementsph::study
