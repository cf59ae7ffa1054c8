// Engine oracles (model-notes 4) and hard cases.
#include "SPHTestScenes.h"

#include "cementsph/sph/DarcyBenchmark.h"
#include "cementsph/sph/Presets.h"

#include <gtest/gtest.h>

#include <random>

using namespace cementsph::sph;
using namespace cementsph::sph::testing;

TEST(SPHSimulation, InteriorLatticeDensityIsRestDensityAtDefaultSmoothingLength) {
  const double d = 1e-3;
  ModelParameters m = baseModel(d, modelPreset("default").hOverD);
  auto sim = periodicLattice(m, 10, d);
  sim->updateDensityAndPressure();
  for (std::size_t i = 0; i < sim->fluid().size(); ++i)
    ASSERT_NEAR(sim->fluid().density[i] / m.restDensity, 1.0, 0.01) << "particle " << i; // 1 % (issue)
  // Measured: 0.99997 (see VALIDATION.md); the paper's h = d/2 sees no neighbour: 8/pi = 2.546 rho0.
  EXPECT_NEAR(sim->fluid().density[0] / m.restDensity, 0.99997, 1e-4);
  auto paper = periodicLattice(baseModel(d, 0.5), 10, d);
  paper->updateDensityAndPressure();
  EXPECT_NEAR(paper->fluid().density[0] / m.restDensity, 8.0 / kPi, 1e-9);
}

TEST(SPHSimulation, PressureForcesConserveMomentum) {
  // Perturbed lattice in an open box (no fixed particles, no body force): the pairwise pressure
  // forces of Eq. 5 are antisymmetric, so sum_i m_i a_i vanishes to round-off.
  const double d = 1e-3;
  ModelParameters m = baseModel(d);
  m.viscosityModel = ViscosityModel::None;
  m.integrator = Integrator::Explicit;
  Domain domain;
  domain.lower.setConstant(-5 * d);
  domain.upper.setConstant(15 * d);
  Simulation sim(m, domain);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3 * d, 0.3 * d);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i)
        sim.addFluidParticle(Eigen::Vector3d(i * d + jitter(rng), j * d + jitter(rng), k * d + jitter(rng)),
                             Eigen::Vector3d::Zero(), m.restDensity * d * d * d * (1.0 + 0.1 * (i % 3)));
  sim.updateDensityAndPressure();
  sim.updateAccelerations();
  const FluidParticles& f = sim.fluid();
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  double scale = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const Eigen::Vector3d fi = f.mass[i] * Eigen::Vector3d(f.ax[i], f.ay[i], f.az[i]);
    total += fi;
    scale += fi.norm();
  }
  ASSERT_GT(scale, 0.0);
  EXPECT_LT(total.norm(), 1e-12 * scale);
}

TEST(SPHSimulation, DragPermeabilityAtPorosityOneMatchesOracle) {
  // Model-notes 3: at porosity 1 the steady velocity is F / gamma, so k0 = h^5 / (Cf d^3) (1 %).
  // That assumes rho = rho0; at the paper's h = d/2 a particle sees no neighbour, rho = (8/pi) rho0,
  // and gamma ~ 1/rho^2 makes k0 (8/pi)^2 = 6.48 times larger: the same oracle with the summed density.
  for (Integrator integrator : {Integrator::Overdamped, Integrator::CentralDifference}) {
    for (double hOverD : {1.0, 0.5}) {
      const double d = 1e-3, F = 0.5;
      ModelParameters m = baseModel(d, hOverD);
      m.dragCoefficient = 3.0;
      m.integrator = integrator;
      m.bodyForce = Eigen::Vector3d(F, 0, 0);
      auto sim = periodicLattice(m, 8, d);
      for (int s = 0; s < 400; ++s) sim->step();
      double u = 0;
      for (double v : sim->fluid().vx) u += v;
      u /= double(sim->fluid().size());
      const double k = m.viscosity * u / (m.restDensity * F); // Eq. 12 at porosity 1
      const double h = m.smoothingLength;
      const double densityRatio = hOverD == 0.5 ? 8.0 / kPi : 1.0;
      const double k0 = h * h * h * h * h / (m.dragCoefficient * d * d * d) * densityRatio * densityRatio;
      EXPECT_NEAR(k / k0, 1.0, 0.01) << toString(integrator) << " h/d " << hOverD;
      std::cout << toString(integrator) << ", h/d " << hOverD << ": k / k0 = " << k / k0 << "\n";
    }
  }
}

TEST(SPHSimulationHardCases, VeryViscousCementWithPaperIntegratorStaysBounded) {
  // mu = 1e4 Pa.s, central difference at its acoustic step, 1000 steps, porous box: no NaN, and the
  // kinetic energy never exceeds that of free drag-limited flow (u = F / gamma everywhere).
  const double d = 1e-3, F = 2.0;
  ModelParameters m = baseModel(d, 1.0);
  m.viscosity = 1e4;
  m.integrator = Integrator::CentralDifference;
  m.bodyForce = Eigen::Vector3d(F, 0, 0);
  Domain domain;
  domain.upper.setConstant(8 * d);
  domain.periodic = {true, true, true};
  Simulation sim(m, domain);
  std::mt19937_64 rng(3);
  const double mass = m.restDensity * d * d * d;
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i) {
        const Eigen::Vector3d p((i + 0.5) * d, (j + 0.5) * d, (k + 0.5) * d);
        if (rng() % 10 < 3) sim.addFixedParticle(p, mass);
        else sim.addFluidParticle(p, Eigen::Vector3d::Zero(), mass);
      }
  const double gamma = m.dragRate(mass, m.restDensity);
  const double freeEnergy = 0.5 * mass * double(sim.fluid().size()) * (F / gamma) * (F / gamma);
  double maxEnergy = 0;
  for (int s = 0; s < 1000; ++s) {
    ASSERT_NO_THROW(sim.step()) << "step " << s;
    maxEnergy = std::max(maxEnergy, sim.kineticEnergy());
  }
  EXPECT_NEAR(sim.statistics().largestStep, m.acousticCourant * m.smoothingLength / m.soundSpeed, 1e-15);
  EXPECT_TRUE(std::isfinite(maxEnergy));
  EXPECT_LE(maxEnergy, 1.5 * freeEnergy);
}

TEST(SPHSimulationHardCases, TwoParticlesAtOnePositionSeparate) {
  // An extra particle placed exactly on a lattice particle: the pair is over-dense, and the spiky
  // gradient (non-zero at r = 0, Eq. 11) must push them apart without a NaN; momentum stays zero.
  // (An isolated coincident pair is below rest density, 2 m W(0) = 0.64 rho0 at h = d: tension holds
  // it together, which is the model, not a failure.)
  const double d = 1e-3;
  ModelParameters m = baseModel(d);
  m.viscosityModel = ViscosityModel::None;
  m.integrator = Integrator::Explicit;
  auto sim = periodicLattice(m, 6, d);
  const Eigen::Vector3d site = sim->fluid().position(100);
  const std::uint64_t extra = sim->addFluidParticle(site, Eigen::Vector3d::Zero(), m.restDensity * d * d * d);
  for (int s = 0; s < 200; ++s) ASSERT_NO_THROW(sim->step());
  const FluidParticles& f = sim->fluid();
  double nearest = 1.0;
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
  double scale = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    momentum += f.mass[i] * f.velocity(i);
    scale += f.mass[i] * f.velocity(i).norm();
    if (f.id[i] == extra) continue;
    for (std::size_t j = 0; j < f.size(); ++j)
      if (f.id[j] == extra) nearest = std::min(nearest, (f.position(i) - f.position(j)).norm());
  }
  EXPECT_TRUE(std::isfinite(nearest));
  EXPECT_GT(nearest, 0.05 * d);
  EXPECT_LT(momentum.norm(), 1e-12 * scale);
}

TEST(SPHSimulationHardCases, ParticleWithNoNeighboursFollowsTheDrag) {
  // Alone, a particle feels only body force and drag: v = F / gamma with gamma from its self-density.
  const double d = 1e-3, F = 1.0;
  ModelParameters m = baseModel(d);
  m.integrator = Integrator::Overdamped;
  m.bodyForce = Eigen::Vector3d(0, 0, -F);
  Domain domain;
  domain.lower.setConstant(-10 * d);
  domain.upper.setConstant(10 * d);
  Simulation sim(m, domain);
  const double mass = m.restDensity * d * d * d;
  sim.addFluidParticle(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), mass);
  sim.step();
  const double rho = mass * CubicSplineKernel(m.smoothingLength).value(0.0);
  EXPECT_NEAR(sim.fluid().density[0], rho, 1e-12 * rho);
  EXPECT_NEAR(sim.fluid().vz[0], -F / m.dragRate(mass, rho), 1e-12);
  EXPECT_EQ(sim.fluid().vx[0], 0.0);
}

TEST(SPHSimulationHardCases, PorosityZeroIsAClearError) {
  DarcyBenchmark bench(modelPreset("default").model, 1.0);
  DarcyCase c;
  c.porosity = 0.0;
  try {
    bench.run(c);
    FAIL() << "porosity 0 accepted";
  } catch (const SimulationError& e) {
    EXPECT_NE(std::string(e.what()).find("porosity"), std::string::npos) << e.what();
  }
}

TEST(SPHSimulationHardCases, ExplicitMorrisStepOverViscousLimitIsRefusedOrClamped) {
  const double d = 1e-3;
  ModelParameters m = baseModel(d);
  m.viscosity = 100.0;
  m.viscosityModel = ViscosityModel::Morris;
  m.integrator = Integrator::Explicit;
  const double viscousLimit = m.viscousNumber * d * d * m.restDensity / m.viscosity; // 1.475e-6 s
  m.fixedTimeStep = 10 * viscousLimit;
  {
    auto sim = periodicLattice(m, 6, d);
    try {
      sim->step();
      FAIL() << "a step 10x over the viscous limit was taken";
    } catch (const SimulationError& e) {
      EXPECT_NE(std::string(e.what()).find("viscous stability limit"), std::string::npos) << e.what();
    }
  }
  m.stepLimitPolicy = StepLimitPolicy::Clamp;
  auto sim = periodicLattice(m, 6, d);
  const double dt = sim->step();
  EXPECT_NEAR(dt, viscousLimit, 1e-12 * viscousLimit);
  ASSERT_EQ(sim->warnings().size(), 1u);
  EXPECT_NE(sim->warnings()[0].find("clamped"), std::string::npos);
}

TEST(SPHSimulationHardCases, UnstableRunStopsWithWhereAndWhy) {
  // Explicit integration far beyond the acoustic limit on a compressed cluster must stop with a
  // message naming a particle and the cause, not write NaN.
  const double d = 1e-3;
  ModelParameters m = baseModel(d);
  m.viscosityModel = ViscosityModel::None;
  m.integrator = Integrator::Explicit;
  m.acousticCourant = 200.0; // disables the safeguard on purpose
  m.forceCourant = 200.0;
  Domain domain;
  domain.lower.setConstant(-30 * d);
  domain.upper.setConstant(30 * d);
  Simulation sim(m, domain);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i)
        sim.addFluidParticle(Eigen::Vector3d(i, j, k) * 0.5 * d, Eigen::Vector3d::Zero(), m.restDensity * d * d * d);
  try {
    for (int s = 0; s < 100; ++s) sim.step();
    FAIL() << "unstable run was not detected";
  } catch (const SimulationError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("unstable at step"), std::string::npos) << what;
    EXPECT_NE(what.find("fluid particle #"), std::string::npos) << what;
  }
}

TEST(SPHSimulation, ResultsAreDeterministicForAGivenThreadCount) {
  auto run = [] {
    const double d = 1e-3;
    ModelParameters m = baseModel(d);
    m.bodyForce = Eigen::Vector3d(1.0, 0.2, 0);
    Domain domain;
    domain.upper.setConstant(8 * d);
    domain.periodic = {true, true, true};
    Simulation sim(m, domain);
    std::mt19937_64 rng(11);
    for (int k = 0; k < 8; ++k)
      for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
          const Eigen::Vector3d p((i + 0.5) * d, (j + 0.5) * d, (k + 0.5) * d);
          if (rng() % 4 == 0) sim.addFixedParticle(p, 1180 * d * d * d);
          else sim.addFluidParticle(p, Eigen::Vector3d::Zero(), 1180 * d * d * d);
        }
    for (int s = 0; s < 100; ++s) sim.step();
    return sim.fluid().x;
  };
  EXPECT_EQ(run(), run()); // bitwise
}

TEST(SPHSimulationBoundaries, OpenSideRemovesAndCountsEscapedParticles) {
  const double d = 1e-3;
  ModelParameters m = baseModel(d);
  m.integrator = Integrator::Overdamped;
  m.bodyForce = Eigen::Vector3d(50.0, 0, 0);
  Domain domain;
  domain.upper = Eigen::Vector3d(10 * d, 10 * d, 10 * d);
  Simulation sim(m, domain);
  const double mass = m.restDensity * d * d * d;
  sim.addFluidParticle(Eigen::Vector3d(9.9 * d, 5 * d, 5 * d), Eigen::Vector3d::Zero(), mass); // leaves
  sim.addFluidParticle(Eigen::Vector3d(2 * d, 5 * d, 5 * d), Eigen::Vector3d::Zero(), mass);   // stays
  // The leaver moves 0.05 h per step at most: it is out within 0.1 d / (0.05 d) + 1 = 3 steps.
  for (int s = 0; s < 3; ++s) sim.step();
  EXPECT_EQ(sim.escapedCount(), 1u);
  ASSERT_EQ(sim.fluid().size(), 1u);
  EXPECT_EQ(sim.fluid().id[0], 1u);
}

TEST(SPHSimulationBoundaries, PeriodicSideReentersWithSameVelocity) {
  const double d = 1e-3;
  ModelParameters m = baseModel(d);
  m.viscosityModel = ViscosityModel::None;
  m.integrator = Integrator::Explicit;
  Domain domain;
  domain.upper.setConstant(10 * d);
  domain.periodic = {true, true, true};
  Simulation sim(m, domain);
  const Eigen::Vector3d v(0.2, 0, 0);
  sim.addFluidParticle(Eigen::Vector3d(9.97 * d, 5 * d, 5 * d), v, m.restDensity * d * d * d);
  const double dt = sim.step(); // alone: no force, so it drifts at v
  EXPECT_EQ(sim.escapedCount(), 0u);
  ASSERT_GT(9.97 * d + v.x() * dt, 10 * d); // it did cross
  EXPECT_NEAR(sim.fluid().x[0], 9.97 * d + v.x() * dt - 10 * d, 1e-15);
  EXPECT_EQ(sim.fluid().vx[0], v.x());
}
