// Unit checks of the injection pieces: Hagen-Poiseuille (Eq. 13) against model-notes 4, the viscosity
// schedule, the cannula's emission pattern and count, the tip probe's Eq. 2 density, and the voxeliser (Eq. 2
// with h = 2r at voxel centres, the paper's simulated CT).
#include "SPHTestScenes.h"

#include "cementsph/sph/CannulaEmitter.h"
#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/ParticleVoxeliser.h"
#include "cementsph/sph/TipPressureProbe.h"
#include "cementsph/sph/ViscositySchedule.h"

#include <gtest/gtest.h>

#include <iostream>
#include <random>

using namespace cementsph::sph;
using namespace cementsph::sph::testing;

namespace {
constexpr double kMl = 1e-6; // m^3
constexpr double kQ = 0.05 * kMl;

template <class F> std::string thrownMessage(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
} // namespace

// ---- Hagen-Poiseuille, Eq. 13 (model-notes 4) ------------------------------------------------------------

TEST(HagenPoiseuille, PressureDropsMatchModelNotes) {
  const double mu[4] = {50, 100, 200, 400};
  const double g11[4] = {0.28, 0.56, 1.13, 2.26}; // MPa, 11G 9 cm, ID 2.388 mm
  const double g8[4] = {0.12, 0.24, 0.47, 0.94};  // MPa, 8G 16 cm, ID 3.429 mm
  for (int k = 0; k < 4; ++k) {
    const double p11 = hagenPoiseuillePressureDrop(mu[k], 0.09, kQ, 2.388e-3) / 1e6;
    const double p8 = hagenPoiseuillePressureDrop(mu[k], 0.16, kQ, 3.429e-3) / 1e6;
    std::cout << mu[k] << " Pa.s: 11G " << p11 << " MPa, 8G " << p8 << " MPa\n";
    EXPECT_NEAR(p11, g11[k], 0.005) << mu[k]; // the notes round to 0.01 MPa
    EXPECT_NEAR(p8, g8[k], 0.005) << mu[k];
  }
  EXPECT_NEAR(boreSpeed(kQ, 2.388e-3) * 1e3, 11.2, 0.05); // mm/s
  EXPECT_NEAR(boreSpeed(kQ, 3.429e-3) * 1e3, 5.4, 0.05);
}

TEST(HagenPoiseuille, ViscosityIsTheInverse) {
  for (double mu : {0.5, 50.0, 400.0, 1e4}) {
    const double dp = hagenPoiseuillePressureDrop(mu, 0.09, kQ, 2.388e-3);
    EXPECT_NEAR(hagenPoiseuilleViscosity(dp, 0.09, kQ, 2.388e-3) / mu, 1.0, 1e-12);
  }
  EXPECT_THROW(hagenPoiseuillePressureDrop(100, 0.09, kQ, 0.0), std::invalid_argument);
  EXPECT_THROW(hagenPoiseuilleViscosity(-1, 0.09, kQ, 2.388e-3), std::invalid_argument);
}

// ---- Viscosity schedule ---------------------------------------------------------------------------------

TEST(ViscositySchedule, ConstantLinearAndTable) {
  EXPECT_DOUBLE_EQ(ViscositySchedule::constant(100).at(37.0), 100.0);
  const ViscositySchedule lin = ViscositySchedule::linear(50, 2.5); // the paper's mu0 + rate t
  EXPECT_DOUBLE_EQ(lin.at(0), 50.0);
  EXPECT_DOUBLE_EQ(lin.at(40), 150.0);
  EXPECT_DOUBLE_EQ(lin.at(-3), 50.0); // before injection: mu0
  const ViscositySchedule tab = ViscositySchedule::table({{0, 50}, {10, 100}, {30, 400}});
  EXPECT_DOUBLE_EQ(tab.at(-1), 50.0);  // clamped at the first point
  EXPECT_DOUBLE_EQ(tab.at(5), 75.0);   // linear interpolation
  EXPECT_DOUBLE_EQ(tab.at(10), 100.0); // at a point
  EXPECT_DOUBLE_EQ(tab.at(20), 250.0);
  EXPECT_DOUBLE_EQ(tab.at(99), 400.0); // clamped at the last point
  EXPECT_DOUBLE_EQ(ViscositySchedule::table({{3, 70}}).at(0), 70.0);
}

TEST(ViscositySchedule, RejectsBadInputWithClearMessages) {
  EXPECT_NE(thrownMessage([] { ViscositySchedule::constant(0); }).find("viscosity must be positive"), std::string::npos);
  EXPECT_NE(thrownMessage([] { ViscositySchedule::linear(-5, 1); }).find("viscosity must be positive"), std::string::npos);
  EXPECT_NE(thrownMessage([] { ViscositySchedule::linear(50, -1); }).find("rate must be zero or positive"), std::string::npos);
  EXPECT_NE(thrownMessage([] { ViscositySchedule::table({}); }).find("at least one"), std::string::npos);
  const std::string nonIncreasing = thrownMessage([] { ViscositySchedule::table({{0, 50}, {10, 60}, {10, 70}}); });
  std::cout << nonIncreasing << "\n";
  EXPECT_NE(nonIncreasing.find("times must increase strictly"), std::string::npos);
  EXPECT_NE(nonIncreasing.find("point 2"), std::string::npos);
  const std::string negative = thrownMessage([] { ViscositySchedule::table({{0, 50}, {10, -60}}); });
  std::cout << negative << "\n";
  EXPECT_NE(negative.find("point 1"), std::string::npos);
}

TEST(ViscositySchedule, SetsTheSimulationsViscosity) {
  auto sim = periodicLattice(baseModel(1e-3), 6, 1e-3);
  sim->setViscosity(ViscositySchedule::linear(50, 2).at(10.0)); // 10 s after the start: 50 + 2 x 10 by hand
  EXPECT_DOUBLE_EQ(sim->parameters().viscosity, 70.0);
}

// ---- Cannula emitter ------------------------------------------------------------------------------------

TEST(CannulaEmitter, LayerPatternCoversTheBoreSymmetrically) {
  CannulaSpec spec; // 11G, d = 1.14 mm
  spec.direction = Eigen::Vector3d(1, 2, -2);
  spec.tip = Eigen::Vector3d(1e-3, 2e-3, 3e-3);
  const CannulaEmitter e(spec);
  const Eigen::Vector3d axis = spec.direction.normalized();
  // (pi D^2 / 4) / d^2 = 3.45: the lattice with the axis between four points (4) is nearer than the centred one (5).
  ASSERT_EQ(e.particlesPerLayer(), 4u);
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : e.layerPattern()) {
    EXPECT_NEAR((p - spec.tip).dot(axis), 0.0, 1e-15); // in the tip plane
    EXPECT_LT((p - spec.tip).norm(), 0.5 * spec.innerDiameter);
    c += p;
  }
  EXPECT_LT((c / 4.0 - spec.tip).norm(), 1e-15); // centroid on the axis
  const double d3 = std::pow(spec.spacing, 3);
  EXPECT_NEAR(e.layerVolume(), 4 * d3, 1e-24);
  EXPECT_NEAR(e.layerThickness(), 4 * d3 / (kPi * 2.388e-3 * 2.388e-3 / 4), 1e-15); // 1.323 mm
  EXPECT_NEAR(e.exitSpeed(), boreSpeed(spec.flowRate, spec.innerDiameter), 1e-15);
  EXPECT_EQ(e.totalParticles(), 3374u); // floor(5 ml / (1.14 mm)^3) = floor(3374.9)
  CannulaSpec g8 = spec;
  g8.innerDiameter = 3.429e-3; // area ratio 7.11: centred lattice 9 points, shifted 4 -> 9
  EXPECT_EQ(CannulaEmitter(g8).particlesPerLayer(), 9u);
}

TEST(CannulaEmitter, DueCountIsVolumeExact) {
  CannulaSpec spec;
  spec.startTime = 2.0;
  const CannulaEmitter e(spec);
  const double d3 = e.particleVolume();
  EXPECT_EQ(e.dueCount(1.9), 0u);
  EXPECT_EQ(e.dueCount(2.0), 1u); // particle 0 carries [0, d^3)
  for (double t : {2.01, 3.0, 7.77, 50.0, 101.0}) {
    const double qt = spec.flowRate * (t - spec.startTime);
    const double emitted = double(e.dueCount(t)) * d3;
    EXPECT_GT(emitted, qt - 1e-21) << t;
    EXPECT_LT(emitted, qt + d3) << t;
  }
  EXPECT_EQ(e.dueCount(1e4), e.totalParticles());
}

TEST(CannulaEmitter, EmitsAtTheTipWithTheExitVelocity) {
  CannulaSpec spec;
  spec.direction = Eigen::Vector3d(0, -1, 0);
  spec.buildWall = false;
  CannulaEmitter e(spec);
  ModelParameters m = baseModel(spec.spacing);
  Domain domain;
  domain.lower.setConstant(-10e-3);
  domain.upper.setConstant(10e-3);
  Simulation sim(m, domain);
  EXPECT_EQ(e.emit(sim), 1u); // t = 0: particle 0 is due
  EXPECT_EQ(e.emit(sim), 0u); // nothing more until Q t reaches d^3
  const FluidParticles& f = sim.fluid();
  EXPECT_LT((f.position(0) - e.layerPattern()[0]).norm(), 1e-15);
  EXPECT_LT((f.velocity(0) - e.exitSpeed() * spec.direction).norm(), 1e-15); // v0 = Q / (pi D^2 / 4) along the axis
  EXPECT_DOUBLE_EQ(f.mass[0], spec.restDensity * std::pow(spec.spacing, 3));
  EXPECT_EQ(e.emittedIds().size(), 1u);
}

TEST(CannulaEmitter, RejectsBadSpecs) {
  CannulaSpec s;
  s.innerDiameter = 0;
  EXPECT_NE(thrownMessage([&] { CannulaEmitter e(s); }).find("inner diameter"), std::string::npos);
  s = CannulaSpec{};
  s.flowRate = -1;
  EXPECT_NE(thrownMessage([&] { CannulaEmitter e(s); }).find("flow rate"), std::string::npos);
  s = CannulaSpec{};
  s.direction = Eigen::Vector3d::Zero();
  EXPECT_NE(thrownMessage([&] { CannulaEmitter e(s); }).find("direction"), std::string::npos);
  s = CannulaSpec{};
  s.totalVolume = 1e-12;
  EXPECT_NE(thrownMessage([&] { CannulaEmitter e(s); }).find("less than one particle"), std::string::npos);
}

TEST(CannulaEmitter, WallLiesBehindTheTipAndOutsideTheEmissionSlots) {
  CannulaSpec spec;
  spec.direction = Eigen::Vector3d(0, 1, 1);
  const CannulaEmitter e(spec);
  const Eigen::Vector3d axis = spec.direction.normalized();
  const auto wall = e.wallPositions();
  ASSERT_FALSE(wall.empty());
  for (const auto& w : wall) {
    const double along = (w - spec.tip).dot(axis);
    const double radial = ((w - spec.tip) - along * axis).norm();
    EXPECT_LE(along, 1e-15);                                          // nothing ahead of the tip
    EXPECT_GE(along, -spec.wallLength - 1e-12);
    if (radial < 0.5 * spec.innerDiameter) {
      EXPECT_LE(along, -spec.spacing + 1e-12); // bore solid from d behind
    }
  }
  spec.buildWall = false;
  EXPECT_TRUE(CannulaEmitter(spec).wallPositions().empty());
}

// ---- Tip probe: Eq. 2 at a point ------------------------------------------------------------------------

TEST(TipPressureProbe, PointDensityEqualsParticleDensityAtAParticle) {
  const double d = 1e-3;
  ModelParameters m = baseModel(d);
  Domain domain;
  domain.lower.setConstant(-2 * d);
  domain.upper.setConstant(10 * d);
  Simulation sim(m, domain);
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i) {
        const Eigen::Vector3d p(i * d, j * d, k * d);
        if ((i + j + k) % 5 == 0) sim.addFixedParticle(p, m.restDensity * d * d * d);
        else sim.addFluidParticle(p, Eigen::Vector3d::Zero(), m.restDensity * d * d * d);
      }
  sim.updateDensityAndPressure();
  for (std::size_t i = 0; i < sim.fluid().size(); i += 7) {
    EXPECT_NEAR(TipPressureProbe::densityAt(sim, sim.fluid().position(i)) / sim.fluid().density[i], 1.0, 1e-12);
    EXPECT_NEAR(TipPressureProbe::pressureAt(sim, sim.fluid().position(i)), sim.fluid().pressure[i], 1e-9);
  }
  // The probe's mean (fixed share cached) equals the mean of the brute-force point pressures.
  TipPressureProbe probe(TipPressureProbe::ringAroundTip(Eigen::Vector3d(2.5 * d, 2.5 * d, 2.5 * d), Eigen::Vector3d::UnitZ(), 1e-3));
  EXPECT_EQ(probe.points().size(), 6u);
  double direct = 0;
  for (const auto& p : probe.points()) direct += TipPressureProbe::pressureAt(sim, p) / 6.0;
  EXPECT_NEAR(probe.meanPressure(sim), direct, 1e-9);
  EXPECT_NEAR(probe.meanPressure(sim), direct, 1e-9); // second call: from the cache
  EXPECT_THROW(probe.baseline(), std::logic_error); // no sample yet
}

// ---- Voxeliser: Eq. 2 at voxel centres, h = 2r = d -------------------------------------------------------

TEST(ParticleVoxeliser, OneParticleGivesBackItsMass) {
  const double d = 1.14e-3, rho0 = 1180.0, mass = rho0 * d * d * d;
  VoxelGrid grid;
  grid.spacing = Eigen::Vector3d(0.47e-3, 0.47e-3, 0.5e-3); // the paper's CT voxels
  grid.origin = Eigen::Vector3d(-3e-3, -3e-3, -3e-3);
  grid.size = {14, 14, 13};
  const ParticleVoxeliser vox(grid, d); // h = 2r = d
  const double offsets[4][3] = {{0, 0, 0}, {0.1e-3, 0.2e-3, 0.3e-3}, {0.235e-3, 0.235e-3, 0.25e-3}, {-0.17e-3, 0.05e-3, 0.11e-3}};
  for (const auto& o : offsets) {
    const double x = o[0], y = o[1], z = o[2];
    const auto rho = vox.density(&x, &y, &z, &mass, 1);
    const double ratio = vox.integratedMass(rho) / mass;
    std::cout << "voxelised mass / particle mass = " << ratio << "\n";
    EXPECT_NEAR(ratio, 1.0, 0.02); // 2 % (issue)
  }
}

TEST(ParticleVoxeliser, CellGridMatchesBruteForce) {
  const double d = 1.14e-3, h = d;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-4e-3, 4e-3);
  std::vector<double> x(400), y(400), z(400), m(400, 1180.0 * d * d * d);
  for (std::size_t i = 0; i < x.size(); ++i) { x[i] = u(rng); y[i] = u(rng); z[i] = u(rng); }
  VoxelGrid grid;
  grid.spacing = Eigen::Vector3d(0.47e-3, 0.47e-3, 0.5e-3);
  grid.origin = Eigen::Vector3d(-3e-3, -2.5e-3, -3.5e-3); // particles outside the grid too
  grid.size = {12, 11, 13};
  const auto rho = ParticleVoxeliser(grid, h).density(x.data(), y.data(), z.data(), m.data(), x.size());
  const CubicSplineKernel W(h);
  double worst = 0;
  for (int k = 0; k < grid.size[2]; ++k)
    for (int j = 0; j < grid.size[1]; ++j)
      for (int i = 0; i < grid.size[0]; ++i) {
        const Eigen::Vector3d c = grid.centre(i, j, k);
        double ref = 0;
        for (std::size_t p = 0; p < x.size(); ++p) ref += m[p] * W.value((c - Eigen::Vector3d(x[p], y[p], z[p])).norm());
        worst = std::max(worst, std::abs(rho[grid.index(i, j, k)] - ref) / 1180.0);
      }
  EXPECT_LT(worst, 1e-12);
  EXPECT_THROW(ParticleVoxeliser(grid, 0.0), std::invalid_argument);
}
