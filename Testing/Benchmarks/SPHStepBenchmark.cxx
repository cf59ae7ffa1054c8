// Whole SPH steps (neighbour update, density, forces, integration) on the three scenes of issue 2:
//  (a) the Darcy box, 25^3 lattice at porosity 0.7;
//  (b) a 200k-particle periodic fluid box with ~30 neighbours (h/d = 0.96: 4/3 pi (2h)^3 / d^3 = 30);
//  (c) 5k fluid particles among 150k fixed ones at 15 % solid, the shape of the cement scenes.
// Reported counter: fluid-particle-steps per second. Threads: --benchmark_filter and OMP_NUM_THREADS,
// or the /threads argument below. Skin: the second argument (fraction of h; 0 rebuilds every step).
#include "cementsph/sph/CannulaEmitter.h"
#include "cementsph/sph/Presets.h"
#include "cementsph/sph/Simulation.h"
#include "cementsph/sph/TipPressureProbe.h"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <memory>
#include <random>

using namespace cementsph::sph;

namespace {

ModelParameters benchModel(double h, double skin) {
  ModelParameters m;
  m.smoothingLength = h;
  m.viscosity = 100.0;
  m.dragCoefficient = 1.0;
  m.integrator = Integrator::Overdamped;
  m.bodyForce = Eigen::Vector3d(2.0, 0, 0);
  m.neighbourSkin = skin;
  return m;
}

// n^3 lattice in a periodic box; a random `solidFraction` of sites fixed.
std::unique_ptr<Simulation> latticeScene(int n, double d, double hOverD, double solidFraction, double skin,
                                         std::size_t maxFluid = SIZE_MAX) {
  Domain domain;
  domain.upper.setConstant(n * d);
  domain.periodic = {true, true, true};
  auto sim = std::make_unique<Simulation>(benchModel(hOverD * d, skin), domain);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  const double mass = 1180.0 * d * d * d;
  std::size_t fluid = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d p((i + 0.5) * d, (j + 0.5) * d, (k + 0.5) * d);
        if (u(rng) < solidFraction) sim->addFixedParticle(p, mass);
        else if (fluid < maxFluid) { sim->addFluidParticle(p, Eigen::Vector3d::Zero(), mass); ++fluid; }
      }
  return sim;
}

void runSteps(benchmark::State& state, Simulation& sim) {
  omp_set_num_threads(static_cast<int>(state.range(0)));
  for (int i = 0; i < 3; ++i) sim.step(); // warm: lists built, pages touched
  for (auto _ : state) sim.step();
  const double fluid = double(sim.fluid().size());
  state.counters["fluid_particle_steps_per_s"] =
      benchmark::Counter(fluid * double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["fluid"] = fluid;
  state.counters["fixed"] = double(sim.fixed().size());
  state.counters["pairs_per_fluid"] = double(sim.neighbourPairCount()) / fluid;
  state.counters["bytes_per_fixed"] = double(sim.bytesPerFixedParticle());
  state.counters["list_rebuilds"] = double(sim.statistics().neighbourRebuilds);
}

void BM_DarcyBox(benchmark::State& state) {
  auto sim = latticeScene(25, 1e-3, 1.0, 0.3, double(state.range(1)) / 100.0);
  runSteps(state, *sim);
}

void BM_PeriodicBox200k(benchmark::State& state) {
  auto sim = latticeScene(59, 1e-3, 0.96, 0.0, double(state.range(1)) / 100.0); // 205k fluid
  runSteps(state, *sim);
}

void BM_CementShape(benchmark::State& state) {
  // 150k fixed at 15 % solid of a 1M-site box; 5k fluid in one corner region.
  auto sim = latticeScene(100, 1e-3, 1.0, 0.15, double(state.range(1)) / 100.0, 5000);
  runSteps(state, *sim);
}

// (d) A whole injection into empty space: 5 ml at 0.05 ml/s (100 s) through an 11G bore, d = 1.14 mm
// (3374 particles), 100 Pa.s, default preset (overdamped, h = d, Cf = 8.7), at most one particle per step, a
// six-point tip pressure sample every step. One iteration is the whole run. Counters: simulated seconds per
// wall second (real-time factor) and steps.
void BM_Injection100s(benchmark::State& state) {
  omp_set_num_threads(static_cast<int>(state.range(0)));
  double simulated = 0, steps = 0, particles = 0;
  for (auto _ : state) {
    const ModelPreset preset = modelPreset("default");
    CannulaSpec spec;
    spec.buildWall = false;
    CannulaEmitter emitter(spec);
    ModelParameters m = preset.model;
    m.smoothingLength = preset.hOverD * spec.spacing;
    m.viscosity = 100.0;
    m.maxTimeStep = emitter.maxTimeStep();
    Domain domain;
    domain.lower.setConstant(-30e-3);
    domain.upper.setConstant(30e-3);
    Simulation sim(m, domain);
    TipPressureProbe probe(TipPressureProbe::ringAroundTip(spec.tip, spec.direction, 0.5 * spec.innerDiameter, 6, spec.spacing));
    const double end = spec.totalVolume / spec.flowRate;
    while (sim.time() < end) {
      emitter.emit(sim);
      sim.step();
      probe.sample(sim);
    }
    simulated += sim.time();
    steps += double(sim.statistics().steps);
    particles = double(sim.fluid().size());
  }
  state.counters["real_time_factor"] = benchmark::Counter(simulated, benchmark::Counter::kIsRate);
  state.counters["steps"] = steps / double(state.iterations());
  state.counters["fluid"] = particles;
}

} // namespace

// Args: {threads, skin in percent of h}. Skin 0 rebuilds the lists every step: the rows at equal
// thread counts answer whether reusing lists pays.
#define CEMENTSPH_STEP_ARGS ->Args({1, 0})->Args({1, 20})->Args({1, 50})->Args({2, 0})->Args({2, 20}) \
    ->Unit(benchmark::kMillisecond)->UseRealTime()
BENCHMARK(BM_DarcyBox) CEMENTSPH_STEP_ARGS;
BENCHMARK(BM_PeriodicBox200k) CEMENTSPH_STEP_ARGS;
BENCHMARK(BM_CementShape) CEMENTSPH_STEP_ARGS;

BENCHMARK(BM_Injection100s)->Arg(1)->Arg(2)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

BENCHMARK_MAIN();
