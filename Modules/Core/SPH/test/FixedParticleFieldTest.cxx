// The tabulated fixed-particle sums (FixedParticleField) against sums taken pair by pair, and particles
// that join valid neighbour lists (Simulation's newcomers) against full rebuilds.
#include "cementsph/sph/CannulaEmitter.h"
#include "cementsph/sph/FixedParticleField.h"
#include "cementsph/sph/Presets.h"
#include "cementsph/sph/Simulation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

namespace cementsph::sph {
namespace {

constexpr double kD = 1.14e-3;       // particle spacing d [m] (the paper's r = 0.57 mm)
constexpr double kVoxel = 0.47e-3;   // solid lattice spacing [m] (the phantom's voxels)
constexpr double kHalfWidth = 7e-3;  // box half-width [m]

// Cement injected at the centre of an open box whose lattice sites are solid with probability 0.25
// (seeded): a porous solid with ~120 fixed particles in a cement particle's support, as in a CT scene.
struct PorousInjection {
  std::unique_ptr<CannulaEmitter> emitter;
  std::unique_ptr<Simulation> sim;
};

PorousInjection makePorousInjection(FixedSumMethod sums, bool relisting, double fieldSpacing = 0.25) {
  const ModelPreset preset = modelPreset("default");
  CannulaSpec spec;
  spec.direction = Eigen::Vector3d::UnitZ();
  spec.flowRate = 0.05e-6;
  spec.totalVolume = 0.2e-6;
  spec.spacing = kD;
  spec.restDensity = preset.model.restDensity;
  spec.buildWall = false;
  auto emitter = std::make_unique<CannulaEmitter>(spec);
  ModelParameters m = preset.model;
  m.smoothingLength = preset.hOverD * kD;
  m.viscosity = 100.0;
  m.maxTimeStep = emitter->maxTimeStep();
  m.fixedSums = sums;
  m.fixedFieldSpacing = fieldSpacing;
  m.relisting = relisting;
  Domain domain;
  domain.lower.setConstant(-kHalfWidth);
  domain.upper.setConstant(kHalfWidth);
  auto sim = std::make_unique<Simulation>(m, domain);
  std::mt19937 rng(7);
  std::bernoulli_distribution solid(0.25);
  const int n = static_cast<int>(2 * kHalfWidth / kVoxel);
  const double mass = 8.0 * m.restDensity * kVoxel * kVoxel * kVoxel;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d p = domain.lower + kVoxel * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5);
        // Keep the bore in front of the tip open so the first particles have somewhere to go.
        if (solid(rng) && !(p.head<2>().norm() < 1.5e-3 && std::abs(p.z()) < 1.5e-3)) sim->addFixedParticle(p, mass);
      }
  return {std::move(emitter), std::move(sim)};
}

// Runs to `seconds`, then updates the density so that the table covers the particles' final positions.
void runFor(PorousInjection& s, double seconds) {
  while (s.sim->time() < seconds) {
    s.emitter->emit(*s.sim);
    s.sim->step();
  }
  s.sim->updateDensityAndPressure();
}

// Pair-by-pair sums over every fixed particle: the independent oracle.
FixedSums bruteForce(const Simulation& sim, const Eigen::Vector3d& x) {
  const CubicSplineKernel cubic(sim.parameters().smoothingLength);
  const SpikyKernel spiky(sim.parameters().smoothingLength);
  FixedSums s;
  const FixedParticles& f = sim.fixed();
  for (std::size_t j = 0; j < f.size(); ++j) {
    const Eigen::Vector3d r = x - Eigen::Vector3d(f.x[j], f.y[j], f.z[j]);
    const double d = r.norm();
    if (d >= cubic.support()) continue;
    s.density += f.mass[j] * cubic.value(d);
    if (d > 0) for (int a = 0; a < 3; ++a) s.gradient[a] += f.mass[j] * spiky.derivative(d) * r[a] / d;
  }
  return s;
}

TEST(FixedParticleField, NodesHoldTheExactSums) {
  PorousInjection s = makePorousInjection(FixedSumMethod::Tabulated, true);
  runFor(s, 1.0);
  const FixedParticleField& field = s.sim->fixedField();
  ASSERT_GT(field.bricksFilled(), 0u);
  const double spacing = field.nodeSpacing();
  const Eigen::Vector3d lower = s.sim->domain().lower;
  const double rho0 = s.sim->parameters().restDensity;
  double worstDensity = 0, worstGradient = 0, gradientScale = 0;
  const FluidParticles& f = s.sim->fluid();
  for (std::size_t i = 0; i < f.size(); ++i) {
    // The node at the lower corner of the particle's cell: interpolation there returns the node value.
    Eigen::Vector3d node;
    for (int a = 0; a < 3; ++a) {
      const double p = a == 0 ? f.x[i] : a == 1 ? f.y[i] : f.z[i];
      node[a] = lower[a] + std::floor((p - lower[a]) / spacing) * spacing;
    }
    double d, g[3];
    field.sample(node.x(), node.y(), node.z(), d, g);
    const FixedSums exact = bruteForce(*s.sim, node);
    worstDensity = std::max(worstDensity, std::abs(d - exact.density) / rho0);
    for (int a = 0; a < 3; ++a) {
      worstGradient = std::max(worstGradient, std::abs(g[a] - exact.gradient[a]));
      gradientScale = std::max(gradientScale, std::abs(exact.gradient[a]));
    }
  }
  EXPECT_LT(worstDensity, 1e-9);
  ASSERT_GT(gradientScale, 0);
  EXPECT_LT(worstGradient / gradientScale, 1e-9);
}

// Between nodes the table is an interpolation, second order where the sums are smooth. At the cement
// particles of an exact run (where the table is used), on this fine-grained random solid (harder than a
// CT's struts), measured: mean density error 1.2 % of rho0 at h/4 (fixed particles of 8 rho0 V make
// the solid's share several rho0), and it falls ~4x per halving of the spacing.
TEST(FixedParticleField, InterpolationConvergesAtTheParticles) {
  PorousInjection s = makePorousInjection(FixedSumMethod::Exact, true);
  runFor(s, 2.0);
  const Simulation& sim = *s.sim;
  const double h = sim.parameters().smoothingLength, rho0 = sim.parameters().restDensity;
  // The fixed particles binned on a grid of our own (the field's contract), independent of the run's.
  CellGrid grid;
  grid.configure(sim.domain(), 2.0 * h);
  std::vector<std::uint32_t> order, cellStart;
  grid.bin(sim.fixed().x.data(), sim.fixed().y.data(), sim.fixed().z.data(), sim.fixed().size(), order, cellStart);
  FixedParticles binned;
  for (std::uint32_t j : order)
    binned.add({sim.fixed().x[j], sim.fixed().y[j], sim.fixed().z[j]}, sim.fixed().mass[j]);
  const FluidParticles& f = sim.fluid();
  std::vector<FixedSums> exact;
  for (std::size_t i = 0; i < f.size(); ++i) exact.push_back(bruteForce(sim, {f.x[i], f.y[i], f.z[i]}));
  double gradientScale = 0;
  for (const FixedSums& e : exact)
    for (double g : e.gradient) gradientScale = std::max(gradientScale, std::abs(g));
  ASSERT_GT(gradientScale, 0);

  double meanDensity[3], meanGradient[3];
  const double spacings[3] = {0.5, 0.25, 0.125};
  for (int k = 0; k < 3; ++k) {
    FixedParticleField field;
    field.configure(sim.domain(), spacings[k] * h, h);
    field.attach(&binned, &grid, &cellStart);
    field.prepare(f.x.data(), f.y.data(), f.z.data(), f.size());
    meanDensity[k] = meanGradient[k] = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      double d, g[3];
      field.sample(f.x[i], f.y[i], f.z[i], d, g);
      meanDensity[k] += std::abs(d - exact[i].density) / rho0 / static_cast<double>(f.size());
      meanGradient[k] += std::hypot(g[0] - exact[i].gradient[0], g[1] - exact[i].gradient[1], g[2] - exact[i].gradient[2]) /
                         gradientScale / static_cast<double>(f.size());
    }
    std::printf("spacing h*%.3f, %zu particles: mean density error %.3g of rho0, mean gradient error %.3g of its largest "
                "value\n", spacings[k], f.size(), meanDensity[k], meanGradient[k]);
  }
  EXPECT_LT(meanDensity[1], 0.015);
  EXPECT_LT(meanGradient[1], 0.05);
  for (int k = 0; k < 2; ++k) {
    EXPECT_GT(meanDensity[k] / meanDensity[k + 1], 3.0) << "density: second order expected";
    EXPECT_GT(meanGradient[k] / meanGradient[k + 1], 2.5) << "gradient: second order expected";
  }
}

TEST(FixedParticleField, TabulatedRunStaysCloseToExact) {
  PorousInjection tab = makePorousInjection(FixedSumMethod::Tabulated, true);
  PorousInjection exact = makePorousInjection(FixedSumMethod::Exact, true);
  runFor(tab, 2.0);
  runFor(exact, 2.0);
  auto spread = [](const Simulation& sim) {
    const FluidParticles& f = sim.fluid();
    double r = 0;
    for (std::size_t i = 0; i < f.size(); ++i) r += std::sqrt(f.x[i] * f.x[i] + f.y[i] * f.y[i] + f.z[i] * f.z[i]);
    return r / static_cast<double>(f.size());
  };
  ASSERT_EQ(tab.sim->fluid().size(), exact.sim->fluid().size());
  const double a = spread(*tab.sim), b = spread(*exact.sim);
  std::printf("mean distance from the tip: tabulated %.4f mm, exact %.4f mm\n", a * 1e3, b * 1e3);
  EXPECT_NEAR(a, b, 0.02 * kD); // measured 0.0046 mm, 0.4 % of d
}

// Relisting (new particles, and the few that moved half the skin, get lists of their own instead of a
// rebuild of all lists) sums the same pairs as rebuilding: the same run to round-off.
TEST(Relisting, SameRunAsFullRebuilds) {
  for (FixedSumMethod sums : {FixedSumMethod::Exact, FixedSumMethod::Tabulated}) {
    PorousInjection joined = makePorousInjection(sums, true);
    PorousInjection rebuilt = makePorousInjection(sums, false);
    runFor(joined, 4.0);
    runFor(rebuilt, 4.0);
    EXPECT_GT(joined.sim->statistics().relistings, 10 * joined.sim->statistics().neighbourRebuilds);
    EXPECT_EQ(rebuilt.sim->statistics().relistings, 0u);
    const FluidParticles& a = joined.sim->fluid();
    const FluidParticles& b = rebuilt.sim->fluid();
    ASSERT_EQ(a.size(), b.size());
    ASSERT_EQ(joined.sim->statistics().steps, rebuilt.sim->statistics().steps);
    EXPECT_LT(joined.sim->statistics().neighbourRebuilds, rebuilt.sim->statistics().neighbourRebuilds);
    // Storage order differs (rebuilds sort by cell): match particles by id.
    std::vector<std::size_t> where(a.size());
    for (std::size_t i = 0; i < b.size(); ++i) where[b.id[i]] = i;
    double worst = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::size_t j = where[a.id[i]];
      worst = std::max({worst, std::abs(a.x[i] - b.x[j]), std::abs(a.y[i] - b.y[j]), std::abs(a.z[i] - b.z[j])});
    }
    // The same pairs summed in another order: round-off only (measured 3.3e-12 m after 4 s); a pair
    // missed or counted twice moves particles by ~1e-6 m and more.
    EXPECT_LT(worst, 1e-9) << toString(sums);
  }
}

// Forces asked for right after particles were added (no density update in between): the lists and
// densities are brought up to date first, so the result equals the one with the update.
TEST(Relisting, ForcesAfterAnAdditionUpdateTheListsFirst) {
  for (FixedSumMethod sums : {FixedSumMethod::Exact, FixedSumMethod::Tabulated}) {
    PorousInjection a = makePorousInjection(sums, true);
    PorousInjection b = makePorousInjection(sums, true);
    runFor(a, 1.0);
    runFor(b, 1.0);
    const Eigen::Vector3d p(0.0, 0.0, 2.5e-3), v = Eigen::Vector3d::Zero();
    const double m = a.sim->fluid().mass[0];
    a.sim->addFluidParticle(p, v, m);
    b.sim->addFluidParticle(p, v, m);
    a.sim->updateAccelerations();
    b.sim->updateDensityAndPressure();
    b.sim->updateAccelerations();
    const FluidParticles& fa = a.sim->fluid();
    const FluidParticles& fb = b.sim->fluid();
    ASSERT_EQ(fa.size(), fb.size());
    for (std::size_t i = 0; i < fa.size(); ++i) {
      EXPECT_EQ(fa.ax[i], fb.ax[i]) << toString(sums) << " particle " << i;
      EXPECT_EQ(fa.density[i], fb.density[i]) << toString(sums) << " particle " << i;
    }
  }
}

} // namespace
} // namespace cementsph::sph
