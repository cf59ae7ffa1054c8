// Injection into empty space (no fixed particles unless the cannula wall is on): the shared scene of the
// injection tests and benchmark. Default preset model (h = d, overdamped, Cf = 8.7), open box.
#pragma once

#include "cementsph/sph/CannulaEmitter.h"
#include "cementsph/sph/Presets.h"
#include "cementsph/sph/Simulation.h"
#include "cementsph/sph/TipPressureProbe.h"
#include "cementsph/sph/ViscositySchedule.h"

#include <cmath>
#include <functional>
#include <memory>

namespace cementsph::sph::testing {

struct InjectionScene {
  CannulaEmitter emitter;
  std::unique_ptr<Simulation> sim;
  TipPressureProbe probe;
  ViscositySchedule viscosity;

  // Runs until simulation time `until` [s]: viscosity from the schedule, emission, one step, a pressure sample.
  void runUntil(double until, const std::function<void()>& afterStep = {}) {
    while (sim->time() < until) {
      sim->setViscosity(viscosity.at(sim->time() - emitter.spec().startTime));
      emitter.emit(*sim);
      sim->step();
      probe.sample(*sim);
      if (afterStep) afterStep();
    }
  }
};

// Cannula along +z with its tip at the origin, in an open box of half-width `halfWidth`.
inline InjectionScene makeInjectionScene(double viscosityPaS, double flowRate, double totalVolume, bool wall,
                                         double halfWidth = 20e-3, double d = 1.14e-3, double D = 2.388e-3,
                                         double wallMassFactor = CannulaSpec{}.wallMassFactor) {
  const ModelPreset preset = modelPreset("default");
  CannulaSpec spec;
  spec.tip = Eigen::Vector3d::Zero();
  spec.direction = Eigen::Vector3d::UnitZ();
  spec.innerDiameter = D;
  spec.flowRate = flowRate;
  spec.totalVolume = totalVolume;
  spec.spacing = d;
  spec.restDensity = preset.model.restDensity;
  spec.buildWall = wall;
  spec.wallLength = 6 * d;
  spec.wallMassFactor = wallMassFactor;
  CannulaEmitter emitter(spec);
  ModelParameters m = preset.model;
  m.smoothingLength = preset.hOverD * d;
  m.viscosity = viscosityPaS;
  m.maxTimeStep = emitter.maxTimeStep();
  Domain domain;
  domain.lower.setConstant(-halfWidth);
  domain.upper.setConstant(halfWidth);
  auto sim = std::make_unique<Simulation>(m, domain);
  emitter.addWall(*sim);
  // Six probe points on a ring of radius D/2 one spacing ahead of the tip (in the cement, clear of the wall).
  TipPressureProbe probe(TipPressureProbe::ringAroundTip(spec.tip, spec.direction, 0.5 * D, 6, d));
  return {std::move(emitter), std::move(sim), std::move(probe), ViscositySchedule::constant(viscosityPaS)};
}

} // namespace cementsph::sph::testing
