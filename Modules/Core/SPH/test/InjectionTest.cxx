// Injection into empty space (Basafa et al. 2013, "Simulations", without the foam): the default preset model
// (h = d, overdamped, Cf = 8.7), d = 1.14 mm (r = 0.57 mm, the paper's), 11G bore D = 2.388 mm, 0.05 ml/s.
// Checks: volume-exact emission, symmetry about the cannula axis, cloud size against the injected volume
// (compression accounted for through the Eq. 2 densities), tip pressure against viscosity and rate, the
// cannula wall, the voxelised cloud's mass. Small volumes (0.15-1 ml) keep each run to a fraction of a second.
#include "InjectionScene.h"

#include "cementsph/sph/ParticleVoxeliser.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <iostream>
#include <map>

using namespace cementsph::sph;
using namespace cementsph::sph::testing;

namespace {
// These scenes hold at most ~700 particles: one thread is fastest, and on a machine whose cores are busy
// with other runs OpenMP barriers made the wall test take 59 s instead of ~1 s with two threads.
const int kOneThread = [] {
  omp_set_num_threads(1);
  return 1;
}();

constexpr double kMl = 1e-6;
constexpr double kQ = 0.05 * kMl; // m^3/s
constexpr double kD = 1.14e-3;

struct CloudStats {
  Eigen::Vector3d centroid;
  double volume = 0;     // sum m / rho (Eq. 2 densities): the compressed cloud volume
  double meanRadius = 0; // mean distance from the centroid
};

CloudStats cloudStats(const Simulation& sim) {
  const FluidParticles& f = sim.fluid();
  CloudStats s;
  s.centroid.setZero();
  for (std::size_t i = 0; i < f.size(); ++i) {
    s.centroid += f.position(i);
    s.volume += f.mass[i] / f.density[i];
  }
  s.centroid /= double(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) s.meanRadius += (f.position(i) - s.centroid).norm();
  s.meanRadius /= double(f.size());
  return s;
}

// Mean of the raw Eq. 6 probe pressure over samples with t in [from, to].
double meanRawPressure(const TipPressureProbe& probe, double from, double to) {
  double sum = 0;
  int n = 0;
  for (const auto& s : probe.samples())
    if (s.time >= from && s.time <= to) { sum += s.meanPressure; ++n; }
  return n ? sum / n : 0.0;
}
} // namespace

TEST(Injection, EmittedVolumeIsExactAndTheCloudStaysOnTheAxis) {
  InjectionScene scene = makeInjectionScene(100.0, kQ, 0.6 * kMl, /*wall=*/false);
  const double d3 = kD * kD * kD, rho0 = scene.sim->parameters().restDensity;
  for (double t : {1.0, 3.0, 6.0, 9.0, 11.9}) {
    scene.runUntil(t);
    scene.emitter.emit(*scene.sim); // bring the emission up to the current time (runUntil emits before each step)
    const Simulation& sim = *scene.sim;
    const FluidParticles& f = sim.fluid();
    const double qt = kQ * sim.time();
    const double emitted = double(f.size()) * d3;
    double mass = 0;
    for (double m : f.mass) mass += m;
    const CloudStats c = cloudStats(sim);
    const double offAxis = std::hypot(c.centroid.x(), c.centroid.y());
    const double R = std::cbrt(3.0 * c.volume / (4.0 * kPi)); // ball of the cloud's (compressed) volume
    std::cout << "t " << sim.time() << " s: " << f.size() << " particles, (count d^3 - Q t) / d^3 = " << (emitted - qt) / d3
              << ", centroid off axis " << offAxis / kD << " d, along " << c.centroid.z() / kD
              << " d, sum m/rho / Q t = " << c.volume / qt << ", mean radius / (3R/4) = " << c.meanRadius / (0.75 * R)
              << ", steps " << sim.statistics().steps << "\n";
    EXPECT_EQ(sim.escapedCount(), 0u);
    EXPECT_GE(emitted - qt, -1e-6 * d3) << t; // volume-exact: 0 <= count d^3 - Q t < d^3
    EXPECT_LT(emitted - qt, d3) << t;
    EXPECT_NEAR(mass / (rho0 * emitted), 1.0, 1e-12); // mass rho0 d^3 each
    EXPECT_LT(offAxis, 0.1 * kD) << t;                // symmetric about the axis
    if (t >= 3.0) {
      // Compression: the cloud's volume from the Eq. 2 densities is below Q t by the mean compression
      // (model pressure ~1 kPa against rho0 cs^2 = 1.18 kPa; measured 0.82-0.86 at 100 Pa.s).
      EXPECT_GT(c.volume / qt, 0.75) << t;
      EXPECT_LT(c.volume / qt, 1.0) << t;
      // Shape: a ball of that volume has mean distance 3R/4 from its centre (model-notes 4); the cloud is
      // denser at its centre, so somewhat below (measured 0.91-0.93).
      EXPECT_NEAR(c.meanRadius / (0.75 * R), 1.0, 0.12) << t;
    }
  }
}

TEST(Injection, StateDependsOnViscosityTimesRateOnly) {
  // The overdamped model has v = a / gamma with gamma proportional to mu, and every step limit scales with it:
  // at equal injected volume, (mu, 2Q) and (2 mu, Q) must give the same cloud.
  InjectionScene a = makeInjectionScene(200.0, kQ, 0.1 * kMl, false);
  InjectionScene b = makeInjectionScene(100.0, 2 * kQ, 0.1 * kMl, false);
  a.runUntil(2.0);
  b.runUntil(1.0);
  ASSERT_EQ(a.sim->fluid().size(), b.sim->fluid().size());
  ASSERT_EQ(a.sim->statistics().steps, b.sim->statistics().steps);
  std::map<std::uint64_t, Eigen::Vector3d> pa;
  for (std::size_t i = 0; i < a.sim->fluid().size(); ++i) pa[a.sim->fluid().id[i]] = a.sim->fluid().position(i);
  double worst = 0;
  for (std::size_t i = 0; i < b.sim->fluid().size(); ++i)
    worst = std::max(worst, (pa.at(b.sim->fluid().id[i]) - b.sim->fluid().position(i)).norm());
  std::cout << "largest position difference " << worst / kD << " d after " << a.sim->statistics().steps << " steps\n";
  EXPECT_LT(worst, 1e-6 * kD);
}

TEST(Injection, TipPressureRisesWithViscosityAndRate) {
  // Short runs: 0.15 ml. Viscosity series at 0.05 ml/s: the paper's baseline-subtracted pressure, mean over
  // the second half of the injection.
  std::vector<double> relative;
  for (double mu : {50.0, 100.0, 200.0, 400.0}) {
    InjectionScene s = makeInjectionScene(mu, kQ, 0.15 * kMl, false);
    s.runUntil(3.0);
    relative.push_back(s.probe.meanRelativePressure(1.5));
    std::cout << mu << " Pa.s, 0.05 ml/s: baseline " << s.probe.baseline() << " Pa, tip pressure (t >= 1.5 s) "
              << relative.back() << " Pa\n";
  }
  for (std::size_t k = 1; k < relative.size(); ++k) EXPECT_GT(relative[k], relative[k - 1] * 1.05) << k;
  // Rate series at 100 Pa.s, compared at equal injected volume (the last half of the 0.15 ml): the raw Eq. 6
  // pressure. The paper's 0.5 s baseline is not comparable across rates (it holds 0.5 Q / d^3 particles:
  // more particles, less under-dense, at higher rates), so it is printed, not compared.
  std::vector<double> raw;
  for (double q : {0.025, 0.05, 0.1}) {
    InjectionScene s = makeInjectionScene(100.0, q * kMl, 0.15 * kMl, false);
    const double T = 0.15 / q;
    s.runUntil(T);
    raw.push_back(meanRawPressure(s.probe, 0.5 * T, T));
    std::cout << "100 Pa.s, " << q << " ml/s: tip pressure over the last half " << raw.back()
              << " Pa (baseline-subtracted " << s.probe.meanRelativePressure(0.5 * T) << " Pa)\n";
  }
  for (std::size_t k = 1; k < raw.size(); ++k) EXPECT_GT(raw[k], raw[k - 1] * 1.05) << k;
}

TEST(Injection, CannulaWallKeepsTheCementOutOfTheBore) {
  // 400 Pa.s, the stiffest case: no fluid particle gets into the bore behind its solid face (one spacing
  // behind the tip), and none escapes.
  InjectionScene s = makeInjectionScene(400.0, kQ, 1.0 * kMl, /*wall=*/true);
  s.runUntil(20.0);
  const FluidParticles& f = s.sim->fluid();
  const double L = s.emitter.spec().wallLength, R = 0.5 * s.emitter.spec().innerDiameter;
  int inBore = 0;
  double deepest = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (std::hypot(f.x[i], f.y[i]) >= R || f.z[i] >= 0 || f.z[i] < -L) continue;
    deepest = std::min(deepest, f.z[i]);
    if (f.z[i] < -kD) ++inBore;
  }
  const CloudStats c = cloudStats(*s.sim);
  std::cout << s.sim->fixed().size() << " wall particles; deepest fluid particle in the bore " << deepest / kD
            << " d; centroid ahead of the tip " << c.centroid.z() / kD << " d, off axis "
            << std::hypot(c.centroid.x(), c.centroid.y()) / kD << " d\n";
  EXPECT_EQ(inBore, 0);
  EXPECT_EQ(s.sim->escapedCount(), 0u);
  EXPECT_GT(c.centroid.z(), 0.0); // the wall pushes the cloud forward
  EXPECT_LT(std::hypot(c.centroid.x(), c.centroid.y()), 0.1 * kD);
}

TEST(Injection, ViscosityScheduleIsThePapersLinearRise) {
  // The paper's linear rise mu(t) = mu0 + rate t, by hand at chosen times: 50 + 25 t Pa.s.
  const ViscositySchedule s = ViscositySchedule::linear(50.0, 25.0);
  EXPECT_DOUBLE_EQ(s.at(0.0), 50.0);
  EXPECT_DOUBLE_EQ(s.at(2.0), 100.0);
  EXPECT_DOUBLE_EQ(s.at(4.4), 160.0);
  EXPECT_DOUBLE_EQ(s.at(100.0), 2550.0);
  EXPECT_DOUBLE_EQ(s.at(-3.0), 50.0); // before the injection starts: mu0
  // A table: piecewise linear between (0 s, 50), (10 s, 150), (20 s, 450); held outside.
  const ViscositySchedule t = ViscositySchedule::table({{0.0, 50.0}, {10.0, 150.0}, {20.0, 450.0}});
  EXPECT_DOUBLE_EQ(t.at(5.0), 100.0);
  EXPECT_DOUBLE_EQ(t.at(15.0), 300.0);
  EXPECT_DOUBLE_EQ(t.at(30.0), 450.0);
  EXPECT_DOUBLE_EQ(t.at(-1.0), 50.0);
}

TEST(Injection, ViscosityScheduleDrivesTheDrag) {
  // The engine must use mu(t) in its Eq. 9 drag at every step: an isolated particle under a body force g
  // moves, overdamped, at v = g / gamma with gamma = Cf m mu / (rho^2 h^5) and rho = m W(0) = m / (pi h^3),
  // so gamma = Cf mu pi^2 h / m and v = g m / (Cf pi^2 h mu(t)): v mu(t) is constant and v(t) / v(0) =
  // mu(0) / mu(t). The schedule is applied with an injection start of 1 s (times before it read mu0).
  const double h = kD, m = 1180.0 * kD * kD * kD, Cf = 8.7, g = 1.0, pi = 3.14159265358979323846;
  ModelParameters p;
  p.restDensity = 1180.0;
  p.smoothingLength = h;
  p.dragCoefficient = Cf;
  p.viscosityModel = ViscosityModel::Drag;
  p.integrator = Integrator::Overdamped;
  p.bodyForce = Eigen::Vector3d(0, 0, -g);
  p.fixedTimeStep = 0.125; // s, a power of two: the step times 0.125 k are exact
  Domain domain;
  domain.lower.setConstant(-10 * kD); // it falls by far less than a spacing
  domain.upper.setConstant(10 * kD);
  const ViscositySchedule schedule = ViscositySchedule::linear(50.0, 25.0);
  p.viscosity = schedule.at(0.0);
  Simulation sim(p, domain);
  sim.addFluidParticle(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), m);
  int checked = 0;
  while (sim.time() < 5.0) {
    const double t = sim.time();
    sim.setViscosity(schedule.at(sim.time() - 1.0)); // the injection starts at 1 s
    sim.step();
    const double mu = t < 1.0 ? 50.0 : 50.0 + 25.0 * (t - 1.0); // by hand
    const double v = g * m / (Cf * pi * pi * h * mu);
    ASSERT_NEAR(-sim.fluid().vz[0], v, 1e-12 * v) << "t " << t << " s, mu " << mu << " Pa.s";
    ++checked;
  }
  EXPECT_EQ(checked, 40);
}

TEST(Injection, VoxelisedCloudHoldsTheInjectedMass) {
  InjectionScene s = makeInjectionScene(100.0, kQ, 0.3 * kMl, false);
  s.runUntil(6.0);
  VoxelGrid grid; // the paper's CT voxels, 16 mm cube about the tip
  grid.spacing = Eigen::Vector3d(0.47e-3, 0.47e-3, 0.5e-3);
  grid.size = {35, 35, 33};
  grid.origin = -0.5 * Eigen::Vector3d(34 * 0.47e-3, 34 * 0.47e-3, 32 * 0.5e-3);
  const ParticleVoxeliser vox(grid, kD); // h = 2r = d
  const auto rho = vox.density(s.sim->fluid());
  double mass = 0;
  for (double m : s.sim->fluid().mass) mass += m;
  const double ratio = vox.integratedMass(rho) / mass;
  std::cout << "voxelised mass / injected mass - 1 = " << ratio - 1.0 << " (" << s.sim->fluid().size() << " particles)\n";
  EXPECT_NEAR(ratio, 1.0, 0.02);
}
