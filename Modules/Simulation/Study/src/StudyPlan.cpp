#include "cementsph/study/StudyPlan.h"

#include "cementsph/sph/ModelParameters.h"
#include "cementsph/sph/Presets.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace cementsph::study {

namespace {

std::string show(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

void checkPositiveUnique(const std::vector<double>& values, const std::string& option) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i]) || values[i] <= 0)
      throw std::invalid_argument(option + ": " + show(values[i]) + " is not a positive number");
    for (std::size_t j = 0; j < i; ++j)
      if (values[j] == values[i]) throw std::invalid_argument(option + ": " + show(values[i]) + " is given twice");
  }
}

} // namespace

int integratorFaithfulness(const std::string& integrator) {
  switch (sph::parseIntegrator(integrator)) {
  case sph::Integrator::CentralDifference: return 2;
  case sph::Integrator::Explicit: return 1;
  case sph::Integrator::Overdamped: return 0;
  }
  return 0;
}

scene::SceneConfig StudyRunSpec::scene(const scene::SceneConfig& base) const {
  scene::SceneConfig s = base;
  s.particleRadiusMm = particleRadiusMm;
  s.integrator = integrator;
  s.viscosityPaS = viscosityPaS;
  // A study of particle radius and integrator is a study of the particle model: "auto" (which picks the
  // voxel-grid Darcy filling for creeping flow, where the particle radius means nothing) runs the paper's
  // equation of state here. A study plan that names a pressure model keeps it.
  if (s.pressureModel == "auto") s.pressureModel = "equation-of-state";
  return s;
}

std::string StudyRunSpec::name() const {
  std::ostringstream s;
  if (sweep == Sweep::Viscosity) s << "viscosity_" << viscosityPaS << "pa_s";
  else s << integrator << "_r" << std::fixed << std::setprecision(2) << particleRadiusMm << "mm";
  return s.str();
}

void StudyPlan::validate() {
  baseScene.validate();
  if (sizeStudy) {
    if (radiiMm.empty()) throw std::invalid_argument("--radii-mm: no radius given");
    if (integrators.empty()) throw std::invalid_argument("--integrators: no integrator given");
    checkPositiveUnique(radiiMm, "--radii-mm");
    for (std::string& name : integrators) {
      try {
        name = sph::toString(sph::parseIntegrator(name));
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(std::string("--integrators: ") + e.what());
      }
    }
    for (std::size_t i = 0; i < integrators.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (integrators[i] == integrators[j])
          throw std::invalid_argument("--integrators: " + integrators[i] + " is given twice");
  }
  checkPositiveUnique(viscositiesPaS, "--viscosities-pa-s");
  if (!viscositiesPaS.empty() && (baseScene.viscosityRatePaPerS || !baseScene.viscosityTable.empty()))
    throw std::invalid_argument("--viscosities-pa-s: the scene's viscosity is not constant (it has " +
                                std::string(baseScene.viscosityRatePaPerS ? "viscosity_rate_pa_per_s" : "viscosity_table") +
                                "); a sweep sets a constant viscosity_pa_s");
  if (!sizeStudy && viscositiesPaS.empty())
    throw std::invalid_argument("nothing to run: the size study is off and no --viscosities-pa-s were given");
  // Every run's scene must be valid too (a radius the scene cannot take is refused before any run).
  for (const auto& runs : {sizeRuns(), viscosityRuns()})
    for (const StudyRunSpec& run : runs) run.scene(baseScene).validate();
}

std::vector<StudyRunSpec> StudyPlan::sizeRuns() const {
  std::vector<StudyRunSpec> runs;
  if (!sizeStudy) return runs;
  for (const std::string& integrator : integrators)
    for (double r : radiiMm) {
      StudyRunSpec run;
      run.sweep = StudyRunSpec::Sweep::ParticleSize;
      run.particleRadiusMm = r;
      run.integrator = integrator;
      run.viscosityPaS = baseScene.viscosityPaS;
      runs.push_back(run);
    }
  if (!referenceIsCt && !runs.empty()) {
    // The finest run: smallest radius, then the most faithful integrator.
    auto finer = [](const StudyRunSpec& a, const StudyRunSpec& b) {
      if (a.particleRadiusMm != b.particleRadiusMm) return a.particleRadiusMm < b.particleRadiusMm;
      return integratorFaithfulness(a.integrator) > integratorFaithfulness(b.integrator);
    };
    auto ref = std::min_element(runs.begin(), runs.end(), finer);
    ref->reference = true;
    std::rotate(runs.begin(), ref, ref + 1); // the reference first, the others in their order
  }
  return runs;
}

std::vector<StudyRunSpec> StudyPlan::viscosityRuns() const {
  std::vector<StudyRunSpec> runs;
  for (double mu : viscositiesPaS) {
    StudyRunSpec run;
    run.sweep = StudyRunSpec::Sweep::Viscosity;
    run.particleRadiusMm = baseScene.particleRadiusMm;
    run.integrator = baseScene.integrator ? sph::toString(sph::parseIntegrator(*baseScene.integrator))
                                          : sph::toString(sph::modelPreset(baseScene.modelPreset).model.integrator);
    run.viscosityPaS = mu;
    runs.push_back(run);
  }
  return runs;
}

} // namespace cementsph::study
