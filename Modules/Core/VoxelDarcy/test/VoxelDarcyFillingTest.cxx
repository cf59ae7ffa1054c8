// Oracles of the voxel-grid Darcy filling (VoxelDarcyFilling.h), each against an exact solution of
// Darcy's law (issue "Physical cement"):
//  * a point source in a uniform medium fills a ball, V = 4/3 pi phi R^3; the pressure outside the outlet
//    is p(r) = mu Q / (4 pi k) (1/r - 1/R), and the mean over an outlet ball of radius a with a uniform
//    source is p(a) + mu Q / (20 pi k a) (div q = s inside it), i.e. mu Q / (4 pi k) (1.2 / a - 1 / R);
//  * on an impermeable plane the same source fills a hemisphere of radius 2^(1/3) R;
//  * the pressure is proportional to the viscosity and the cement's shape does not depend on it;
//  * the cement's volume is the injected volume at every step;
//  * the preconditioned solver (MIC(0) conjugate gradient) against a direct solve (Eigen's SimplicialLDLT),
//    and the whole step's pressure against a system assembled here, densely, from the fill it started from;
//  * the active-set bookkeeping (issue 23) against dense passes over every voxel: the cement volume, the
//    voxels with cement, the viscosity after a change, and the same fill in a region three times as wide;
//  * the brick storage (issue 23): its index arithmetic against plain division and lookups, and the bricks a
//    run allocates against those its cement and front touch, counted here, the same in a region 27 times
//    the volume.
#include "cementsph/voxeldarcy/VoxelDarcyFilling.h"
#include "cementsph/rheology/Rheology.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace cementsph::voxeldarcy {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Ball {
  double meanDistance = 0, cementVolume = 0, tipPressure = 0, sourceBallRadius = 0;
};

// Injects `volume` [m^3] at `flowRate` [m^3/s] from `tip`; checks the volume at every step.
void inject(VoxelDarcyFilling& filling, double flowRate, double volume) {
  const double T = volume / flowRate;
  int steps = 0;
  while (filling.time() < T * (1 - 1e-12)) {
    filling.step(flowRate, std::min(T - filling.time(), 0.05 * T));
    ASSERT_NEAR(filling.cementVolume(), filling.injectedVolume(), 1e-9 * volume) << "step " << steps;
    ASSERT_LT(++steps, 100000);
  }
}

double meanDistance(const VoxelDarcyFilling& filling, const Eigen::Vector3d& tip) {
  const VoxelMedium& m = filling.medium();
  double sum = 0, weight = 0;
  for (std::size_t c = 0; c < m.count(); ++c) {
    const double v = filling.fill()[c] * m.porosity[c];
    if (v <= 0) continue;
    sum += v * (m.centre(c) - tip).norm();
    weight += v;
  }
  return sum / weight;
}

double sourceBallRadius(const VoxelDarcyFilling& filling) {
  return std::cbrt(3.0 * double(filling.sourceVoxels().size()) * filling.medium().voxelVolume() / (4 * kPi));
}

// 0.5 mm voxels, 61^3, the tip at the centre voxel.
VoxelMedium cube(double porosity, double permeability) {
  const double h = 0.5e-3;
  return VoxelMedium::uniform({61, 61, 61}, Eigen::Vector3d::Constant(-30 * h), Eigen::Vector3d::Constant(h), porosity,
                              permeability);
}

const double kMu = 100.0, kQ = 5e-8, kK = 1e-9, kVolume = 1e-6; // Pa s, m^3/s (0.05 ml/s), m^2, 1 ml

class Sphere : public ::testing::TestWithParam<double> {};

TEST_P(Sphere, FillsTheBallOfItsPorosityWithDarcysPressure) {
  const double phi = GetParam();
  VoxelDarcyFilling filling(cube(phi, kK));
  const Eigen::Vector3d tip = Eigen::Vector3d::Zero();
  filling.setSource(tip, 1.5e-3); // 3 voxels
  filling.setViscosity(kMu);
  inject(filling, kQ, kVolume);
  const double R = std::cbrt(3 * kVolume / (4 * kPi * phi));
  // Mean distance of a ball's volume from its centre: 3R/4; within 3 % (the tolerance).
  const double d = meanDistance(filling, tip);
  std::printf("phi %.2f: mean distance %.4f mm against %.4f mm; %zu steps, %zu CG iterations\n", phi, d * 1e3,
              0.75 * R * 1e3, filling.statistics().steps, filling.statistics().iterations);
  EXPECT_NEAR(d / (0.75 * R), 1.0, 0.03) << "mean distance " << d * 1e3 << " mm, ball " << 0.75 * R * 1e3 << " mm";
  // Tip pressure: the mean over the outlet ball (radius a of the same volume as its voxels), within 10 %.
  const double a = sourceBallRadius(filling);
  const double expected = kMu * kQ / (4 * kPi * kK) * (1.2 / a - 1 / R);
  std::printf("phi %.2f: tip %.1f Pa against Darcy %.1f Pa (a %.4f mm)\n", phi, filling.sourcePressure(), expected,
              a * 1e3);
  EXPECT_NEAR(filling.sourcePressure() / expected, 1.0, 0.10)
      << "tip " << filling.sourcePressure() << " Pa, Darcy " << expected << " Pa (a " << a * 1e3 << " mm)";
  // The profile between the outlet and the front: shells of filled voxels, within 5 %.
  const VoxelMedium& m = filling.medium();
  for (double r : {0.3 * R, 0.5 * R, 0.7 * R}) {
    double sum = 0;
    int count = 0;
    for (std::size_t c = 0; c < m.count(); ++c) {
      const double rc = (m.centre(c) - tip).norm();
      if (filling.filled(c) && std::abs(rc - r) < 0.25e-3) {
        sum += filling.pressure()[c] - kMu * kQ / (4 * kPi * kK) * (1 / rc - 1 / r); // moved to radius r
        ++count;
      }
    }
    ASSERT_GT(count, 10);
    const double profile = kMu * kQ / (4 * kPi * kK) * (1 / r - 1 / R);
    std::printf("phi %.2f: p(%.3f mm) %.1f Pa against %.1f Pa\n", phi, r * 1e3, sum / count, profile);
    EXPECT_NEAR(sum / count / profile, 1.0, 0.05) << "at r = " << r * 1e3 << " mm";
  }
}

INSTANTIATE_TEST_SUITE_P(Porosities, Sphere, ::testing::Values(1.0, 0.5));

TEST(VoxelDarcyFilling, AnImpermeablePlaneMakesAHemisphereOfTwoToTheThirdTheRadius) {
  VoxelMedium m = cube(1.0, kK);
  // Solid below the plane z = -0.25 mm (voxels k <= 29); the outlet on the plane.
  for (std::size_t c = 0; c < m.count(); ++c)
    if (m.ijk(c)[2] <= 29) m.porosity[c] = 0.0f;
  VoxelDarcyFilling filling(m);
  const Eigen::Vector3d tip(0, 0, -0.25e-3);
  filling.setSource(tip + Eigen::Vector3d(0, 0, 1e-6), 1.5e-3); // just above the plane: the first pore layer
  filling.setViscosity(kMu);
  inject(filling, kQ, 0.5e-6);
  const double Rfree = std::cbrt(3 * 0.5e-6 / (4 * kPi));
  const double d = meanDistance(filling, tip);
  std::printf("hemisphere: mean distance %.4f mm, 2^(1/3) x the free ball's %.4f mm\n", d * 1e3,
              0.75 * std::cbrt(2.0) * Rfree * 1e3);
  EXPECT_NEAR(d / (0.75 * std::cbrt(2.0) * Rfree), 1.0, 0.03);
}

// A heterogeneous medium (k log-uniform over two decades, 10 % solid voxels): viscosity 400 against 100 Pa s.
TEST(VoxelDarcyFilling, PressureIsProportionalToViscosityAndTheShapeDoesNotChange) {
  VoxelMedium m = cube(0.8, kK);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (std::size_t c = 0; c < m.count(); ++c) {
    m.permeability[c] = kK * std::pow(10.0, 2 * u(rng) - 1);
    if (u(rng) < 0.1 && m.ijk(c) != std::array<int, 3>{30, 30, 30}) m.porosity[c] = 0.0f;
  }
  auto run = [&](double mu) {
    VoxelDarcyFilling f(m);
    f.setSource(Eigen::Vector3d::Zero(), 1.0e-3);
    f.setViscosity(mu);
    inject(f, kQ, 0.3e-6);
    return f;
  };
  const VoxelDarcyFilling low = run(100.0), high = run(400.0);
  EXPECT_NEAR(high.sourcePressure() / low.sourcePressure(), 4.0, 4.0 * 1e-6);
  double worst = 0;
  for (std::size_t c = 0; c < m.count(); ++c) worst = std::max(worst, std::abs(high.fill()[c] - low.fill()[c]));
  EXPECT_LT(worst, 1e-6);
}

TEST(VoxelDarcyFilling, ACementThatCannotGoOnIsAClearError) {
  // A closed box of 27 pore voxels cannot take 1 ml.
  VoxelMedium m = VoxelMedium::uniform({5, 5, 5}, Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(1e-3), 1.0, kK);
  for (std::size_t c = 0; c < m.count(); ++c) {
    const auto v = m.ijk(c);
    if (v[0] == 0 || v[1] == 0 || v[2] == 0 || v[0] == 4 || v[1] == 4 || v[2] == 4) m.porosity[c] = 0.0f;
  }
  VoxelDarcyFilling filling(m);
  filling.setSource(Eigen::Vector3d::Constant(2e-3), 0.5e-3);
  filling.setViscosity(kMu);
  EXPECT_THROW(
      {
        for (int i = 0; i < 10000; ++i) filling.step(kQ, 1.0);
      },
      FillingError);
  EXPECT_THROW(filling.setSource(Eigen::Vector3d::Zero(), 1e-3), std::invalid_argument); // a solid voxel
}

// A tube of one voxel's section with a closed voxel across it: the cement stops at it; opened
// (openVoxels, as the tract a withdrawn cannula leaves) after the voxel's brick was allocated, the cement
// goes on through it. In one dimension the filling is exact: 9.5 voxels injected fill the first 9 and half
// the tenth (the volume conservation's own answer, independent of the pressure). The closed voxel's flag
// in its brick must go with it: left set, the assembly never links the opened voxel and the second half
// fails with "the pore space connected to the outlet is full".
TEST(VoxelDarcyFilling, AVoxelOpenedAfterTheCementReachedItsBrickLetsTheCementThrough) {
  const double h = 1e-3, pore = h * h * h;
  VoxelMedium m = VoxelMedium::uniform({20, 1, 1}, Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(h), 1.0, kK);
  m.porosity[5] = 0.0f;
  VoxelDarcyFilling filling(m);
  filling.setSource(Eigen::Vector3d::Zero(), 0.1 * h);
  filling.setViscosity(kMu);
  inject(filling, kQ, 4.5 * pore); // (the first 5 voxels hold 5)
  ASSERT_NEAR(filling.fill()[4], 0.5, 1e-9);
  filling.openVoxels({5}, {1.0f}, {kK});
  inject(filling, kQ, 9.5 * pore);
  for (std::size_t c = 0; c < 20; ++c) EXPECT_NEAR(filling.fill()[c], c < 9 ? 1.0 : c == 9 ? 0.5 : 0.0, 1e-9) << "voxel " << c;
}

// A pore-resolved medium's one permeability held as a value (VoxelMedium::uniformPermeability, no array; issue 23)
// against the same value in every voxel of an array: the same filling and pressures bit for bit, also after a
// closed voxel is opened with another permeability (which makes the medium an array from then on). And the
// checks of the medium still name what is wrong.
TEST(VoxelDarcyFilling, AUniformPermeabilityValueIsTheArrayOfItBitForBit) {
  VoxelMedium array = cube(1.0, kK);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<std::size_t> closed;
  for (std::size_t c = 0; c < array.count(); ++c)
    if (u(rng) < 0.3 && (array.centre(c).norm() > 1.2e-3)) {
      array.porosity[c] = 0.0f;
      if (closed.size() < 40 && array.centre(c).norm() < 2.5e-3) closed.push_back(c);
    }
  ASSERT_EQ(closed.size(), 40u);
  VoxelMedium value = array;
  std::vector<double>().swap(value.permeability);
  value.uniformPermeability = kK;
  auto run = [&](const VoxelMedium& m) {
    VoxelDarcyFilling f(m);
    f.setSource(Eigen::Vector3d::Zero(), 1.0e-3);
    f.setViscosity(kMu);
    std::vector<double> pressures;
    inject(f, kQ, 0.1e-6);
    pressures.push_back(f.sourcePressure());
    f.openVoxels(closed, std::vector<float>(closed.size(), 1.0f), std::vector<double>(closed.size(), 3 * kK));
    inject(f, kQ, 0.2e-6);
    pressures.push_back(f.sourcePressure());
    std::vector<double> fill(m.count());
    for (std::size_t c = 0; c < m.count(); ++c) fill[c] = f.fill()[c];
    return std::make_pair(fill, pressures);
  };
  const auto a = run(array), b = run(value);
  EXPECT_GT(a.second[0], 0.0);
  EXPECT_NE(a.second[0], a.second[1]);
  EXPECT_EQ(a.second, b.second);
  ASSERT_EQ(a.first.size(), b.first.size());
  std::size_t differ = 0, filled = 0;
  for (std::size_t c = 0; c < a.first.size(); ++c) {
    differ += a.first[c] != b.first[c];
    filled += a.first[c] > 0;
  }
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(filled, 100u);

  VoxelMedium bad = value;
  bad.uniformPermeability = 0.0;
  EXPECT_THROW(VoxelDarcyFilling{bad}, std::invalid_argument);
  bad = value;
  bad.porosity[7] = std::numeric_limits<float>::quiet_NaN();
  try {
    VoxelDarcyFilling f(bad);
    ADD_FAILURE() << "a NaN porosity was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("porosity nan at voxel"), std::string::npos) << e.what();
  }
  bad = array;
  bad.permeability[array.index(30, 30, 30)] = std::numeric_limits<double>::infinity();
  try {
    VoxelDarcyFilling f(bad);
    ADD_FAILURE() << "an infinite permeability was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("permeability inf m^2 at the pore voxel"), std::string::npos) << e.what();
  }
}

// Radial power-law Darcy flow (issue "Cement rheology"): with mu = K gamma_dot^(n-1) and the Darcy-scale
// shear rate gamma_dot = alpha q / sqrt(k phi) (rheology::darcyShearRate), |grad p| = C q^n with
// C = K alpha^(n-1) (k phi)^((1-n)/2) / k and q = Q / (4 pi r^2), so outside the outlet
// p(r) = C (Q / 4 pi)^n (r^(1-2n) - R^(1-2n)) / (2n - 1): the profile follows r^(1-2n), and at the same
// volume (the same R) the pressure scales as Q^n.
struct PowerLawRun {
  VoxelDarcyFilling filling;
  double R;
};

PowerLawRun injectPowerLaw(double n, double flowRate, double volume, double minimum = 1e-3, double maximum = 1e9) {
  rheology::RheologyParameters p;
  p.consistencyPaSn = kMu;
  p.flowIndex = n;
  p.minimumViscosityPaS = minimum;
  p.maximumViscosityPaS = maximum;
  std::shared_ptr<const rheology::Rheology> law = rheology::makeRheology("power-law", p);
  PowerLawRun run{VoxelDarcyFilling(cube(1.0, kK)), std::cbrt(3 * volume / (4 * kPi))};
  run.filling.setSource(Eigen::Vector3d::Zero(), 1.5e-3);
  run.filling.setViscosity(kMu);
  run.filling.setShearRateViscosity([law](double g) { return law->viscosity(g); }, n, 4);
  inject(run.filling, flowRate, volume);
  return run;
}

TEST(VoxelDarcyFilling, PowerLawPressureProfileFollowsRToTheOneMinusTwoN) {
  const double n = 0.6;
  const PowerLawRun run = injectPowerLaw(n, kQ, kVolume);
  const double alpha = (3 * n + 1) / (4 * n) * 12 / std::sqrt(150.0);
  const double C = kMu * std::pow(alpha, n - 1) * std::pow(kK, 0.5 * (1 - n)) / kK;
  auto analytic = [&](double r) {
    return C * std::pow(kQ / (4 * kPi), n) * (std::pow(r, 1 - 2 * n) - std::pow(run.R, 1 - 2 * n)) / (2 * n - 1);
  };
  const VoxelMedium& m = run.filling.medium();
  for (double r : {0.35 * run.R, 0.5 * run.R, 0.7 * run.R}) {
    double sum = 0;
    int count = 0;
    for (std::size_t c = 0; c < m.count(); ++c) {
      const double rc = m.centre(c).norm();
      if (run.filling.filled(c) && std::abs(rc - r) < 0.25e-3) {
        sum += run.filling.pressure()[c] - (analytic(rc) - analytic(r));
        ++count;
      }
    }
    ASSERT_GT(count, 10);
    std::printf("power law n %.1f: p(%.3f mm) %.1f Pa against %.1f Pa\n", n, r * 1e3, sum / count, analytic(r));
    EXPECT_NEAR(sum / count / analytic(r), 1.0, 0.05) << "at r = " << r * 1e3 << " mm";
  }
}

TEST(VoxelDarcyFilling, PowerLawTipPressureScalesAsTheFlowRateToTheN) {
  for (double n : {0.4, 0.7}) {
    const double single = injectPowerLaw(n, kQ, 0.5e-6).filling.sourcePressure();
    const double twice = injectPowerLaw(n, 2 * kQ, 0.5e-6).filling.sourcePressure();
    std::printf("power law n %.1f: tip pressure ratio at 2Q %.4f against 2^n %.4f\n", n, twice / single, std::pow(2.0, n));
    EXPECT_NEAR(twice / single / std::pow(2.0, n), 1.0, 0.03) << "n " << n;
  }
}

TEST(VoxelDarcyFilling, PowerLawOfIndexOneIsTheNewtonianRunExactly) {
  const PowerLawRun run = injectPowerLaw(1.0, kQ, 0.3e-6);
  VoxelDarcyFilling newtonian(cube(1.0, kK));
  newtonian.setSource(Eigen::Vector3d::Zero(), 1.5e-3);
  newtonian.setViscosity(kMu);
  inject(newtonian, kQ, 0.3e-6);
  EXPECT_EQ(run.filling.statistics().steps, newtonian.statistics().steps);
  EXPECT_NEAR(run.filling.sourcePressure(), newtonian.sourcePressure(), 1e-9 * newtonian.sourcePressure());
  double worst = 0;
  for (std::size_t c = 0; c < newtonian.fill().size(); ++c)
    worst = std::max(worst, std::abs(run.filling.fill()[c] - newtonian.fill()[c]));
  EXPECT_LT(worst, 1e-9);
}

TEST(VoxelDarcyFilling, ViscosityBoundsHoldAndNothingIsNaNAtExtremeFlowIndices) {
  for (double n : {0.2, 1.5}) {
    const PowerLawRun run = injectPowerLaw(n, kQ, 0.2e-6, 10.0, 1e4);
    const auto& mu = run.filling.viscosity();
    for (std::size_t c = 0; c < mu.size(); ++c) {
      if (!run.filling.filled(c)) continue;
      ASSERT_TRUE(std::isfinite(mu[c]) && mu[c] >= 10.0 && mu[c] <= 1e4) << "n " << n << ": " << mu[c];
      ASSERT_TRUE(std::isfinite(run.filling.pressure()[c]));
    }
    EXPECT_TRUE(std::isfinite(run.filling.sourcePressure()) && run.filling.sourcePressure() > 0);
  }
}

// A heterogeneous medium around the origin: k log-uniform over two decades, 10 % solid voxels (not the centre).
VoxelMedium heterogeneous(int size, unsigned seed) {
  const double h = 0.5e-3;
  VoxelMedium m = VoxelMedium::uniform({size, size, size}, Eigen::Vector3d::Constant(-(size / 2) * h),
                                       Eigen::Vector3d::Constant(h), 0.8, kK);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  for (std::size_t c = 0; c < m.count(); ++c) {
    m.permeability[c] = kK * std::pow(10.0, 2 * u(rng) - 1);
    const auto v = m.ijk(c);
    if (u(rng) < 0.1 && v != std::array<int, 3>{size / 2, size / 2, size / 2}) m.porosity[c] = 0.0f;
  }
  return m;
}

// The pressure system a step solves, assembled densely (every voxel visited) from the state before the
// step: unknowns the filled voxels; two-point fluxes with harmonic-mean mobility; ghost-fluid faces to the
// front voxels at p = 0, f of the way across; the flow rate over the filled outlet voxels by pore volume.
Eigen::VectorXd directPressure(const VoxelMedium& m, const std::vector<std::uint8_t>& filled, const std::vector<double>& fill,
                               const std::vector<std::size_t>& source, double mu, double flowRate,
                               std::vector<int>& unknown) {
  const std::size_t n = m.count();
  unknown.assign(n, -1);
  int rows = 0;
  for (std::size_t c = 0; c < n; ++c)
    if (filled[c]) unknown[c] = rows++;
  double sourcePore = 0;
  for (std::size_t c : source)
    if (filled[c]) sourcePore += m.porosity[c];
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(rows);
  const double h = m.spacing[0], area = h * h;
  for (std::size_t c = 0; c < n; ++c) {
    if (!filled[c]) continue;
    const auto v = m.ijk(c);
    const double lc = m.permeability[c] / mu;
    for (int a = 0; a < 3; ++a)
      for (int s : {-1, 1}) {
        std::array<int, 3> w = v;
        w[std::size_t(a)] += s;
        if (w[std::size_t(a)] < 0 || w[std::size_t(a)] >= m.size[a]) continue;
        const std::size_t o = m.index(w[0], w[1], w[2]);
        if (m.porosity[o] <= 0) continue;
        const double lo = m.permeability[o] / mu;
        const double t = filled[o] ? area * 2 * lc * lo / ((lc + lo) * h) : area / (0.5 * h / lc + fill[o] * h / lo);
        entries.emplace_back(unknown[c], unknown[c], t);
        if (filled[o]) entries.emplace_back(unknown[c], unknown[o], -t);
      }
    if (std::find(source.begin(), source.end(), c) != source.end() && sourcePore > 0)
      b[unknown[c]] += flowRate * m.porosity[c] / sourcePore;
  }
  Eigen::SparseMatrix<double> A(rows, rows);
  A.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
  EXPECT_EQ(ldlt.info(), Eigen::Success);
  return ldlt.solve(b);
}

// Appends row `row` (its off-diagonal columns and values, and its diagonal) to A in column order, and to
// `entries` when given.
void appendRow(PressureSystem& A, std::vector<std::pair<int, double>> cols, int row, double diagonal,
               std::vector<Eigen::Triplet<double>>* entries) {
  cols.push_back({row, diagonal});
  std::sort(cols.begin(), cols.end());
  for (const auto& [col, val] : cols) {
    if (col == row) A.diagonal.push_back(int(A.column.size()));
    A.column.push_back(col);
    A.value.push_back(val);
    if (entries) entries->emplace_back(row, col, val);
  }
  A.rowStart.push_back(int(A.column.size()));
}

TEST(VoxelDarcySolver, MicConjugateGradientMatchesADirectSolve) {
  // A 7-point system with varying coefficients, a few Dirichlet faces, and a region of pure Neumann rows.
  const int nx = 12, ny = 10, nz = 9;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  PressureSystem A;
  std::vector<Eigen::Triplet<double>> entries;
  auto id = [&](int i, int j, int k) { return i + nx * (j + ny * k); };
  std::vector<double> tx(std::size_t(nx * ny * nz)), ty(tx.size()), tz(tx.size());
  for (auto* t : {&tx, &ty, &tz})
    for (double& e : *t) e = std::pow(10.0, 2 * u(rng));
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const int row = id(i, j, k);
        double diagonal = i == 0 ? 5.0 : 0.0; // Dirichlet on the x = 0 side
        std::vector<std::pair<int, double>> cols;
        auto link = [&](int ii, int jj, int kk, double t) {
          if (ii < 0 || jj < 0 || kk < 0 || ii >= nx || jj >= ny || kk >= nz) return;
          cols.push_back({id(ii, jj, kk), -t});
          diagonal += t;
        };
        link(i, j, k - 1, tz[std::size_t(id(i, j, k - 1 < 0 ? 0 : k - 1))]);
        link(i, j - 1, k, ty[std::size_t(id(i, j - 1 < 0 ? 0 : j - 1, k))]);
        link(i - 1, j, k, tx[std::size_t(id(i - 1 < 0 ? 0 : i - 1, j, k))]);
        link(i + 1, j, k, tx[std::size_t(row)]);
        link(i, j + 1, k, ty[std::size_t(row)]);
        link(i, j, k + 1, tz[std::size_t(row)]);
        appendRow(A, cols, row, diagonal, &entries);
      }
  const int n = A.rows();
  Eigen::SparseMatrix<double> S(n, n);
  S.setFromTriplets(entries.begin(), entries.end());
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = u(rng) - 0.3;
  const Eigen::VectorXd direct = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(S).solve(b);
  PressureSolver solver;
  for (double tolerance : {1e-6, 1e-12}) {
    Eigen::VectorXd x; // no guess
    const PressureSolver::Result r = solver.solve(A, b, x, tolerance, 1000);
    const double error = (x - direct).lpNorm<Eigen::Infinity>() / direct.lpNorm<Eigen::Infinity>();
    std::printf("MIC(0) CG, tolerance %.0e: %d iterations (of %d unknowns), residual %.2e, error %.2e\n", tolerance,
                r.iterations, n, r.relativeResidual, error);
    EXPECT_TRUE(r.converged);
    EXPECT_LE(r.relativeResidual, tolerance);
    EXPECT_LT(error, tolerance * 1e3);
    // A warm start from the answer takes no iteration.
    const PressureSolver::Result again = solver.solve(A, b, x, tolerance, 1000);
    EXPECT_EQ(again.iterations, 0);
  }
}

// The filling's assembly writes its rows straight into the solver (startRows, setRow, solveRows) instead of
// compressed rows that solve(PressureSystem) pads: the same arithmetic in the same order, so the same
// solution bit for bit and the same iterations. On grids with holes (a -y or -z neighbour is then at times
// the row just before, a +y or +z one the row just after, which the padded layout keeps apart as the -x/+x
// chain), on a line (no lower or upper slot used: the narrower padded layout), on a full block.
TEST(VoxelDarcySolver, RowsWrittenStraightIntoTheSolverGiveTheSameSolutionBitForBit) {
  struct Case { int nx, ny, nz; double keep; };
  for (const Case& g : {Case{3, 11, 9, 0.55}, Case{9, 8, 7, 1.0}, Case{25, 1, 1, 1.0}, Case{2, 12, 6, 0.6}, Case{9, 8, 1, 1.0}}) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    const int cells = g.nx * g.ny * g.nz;
    std::vector<int> row(std::size_t(cells), -1);
    int n = 0;
    for (int c = 0; c < cells; ++c)
      if (u(rng) < g.keep) row[std::size_t(c)] = n++;
    std::vector<double> t(3 * std::size_t(cells));
    for (double& e : t) e = std::pow(10.0, 2 * u(rng));
    PressureSystem A;
    PressureSolver straight;
    straight.startRows(n);
    int previousHits = 0; // rows whose i - 1 coupling is a -y or -z neighbour
    for (int c = 0; c < cells; ++c) {
      const int r = row[std::size_t(c)];
      if (r < 0) continue;
      const int i = c % g.nx, j = (c / g.nx) % g.ny, k = c / (g.nx * g.ny);
      double diagonal = u(rng) < 0.1 ? 3.0 : 0.01; // some Dirichlet rows, and none singular (no closed pocket)
      std::vector<std::pair<int, double>> cols;
      const int step[3] = {1, g.nx, g.nx * g.ny};
      const int at[3] = {i, j, k}, size[3] = {g.nx, g.ny, g.nz};
      for (int a = 2; a >= 0; --a) // -z, -y, -x
        if (at[a] > 0 && row[std::size_t(c - step[a])] >= 0) {
          cols.push_back({row[std::size_t(c - step[a])], -t[3 * std::size_t(c - step[a]) + std::size_t(a)]});
          diagonal += t[3 * std::size_t(c - step[a]) + std::size_t(a)];
        }
      for (int a = 0; a < 3; ++a) // +x, +y, +z
        if (at[a] + 1 < size[a] && row[std::size_t(c + step[a])] >= 0) {
          cols.push_back({row[std::size_t(c + step[a])], -t[3 * std::size_t(c) + std::size_t(a)]});
          diagonal += t[3 * std::size_t(c) + std::size_t(a)];
        }
      double previous = 0, next = 0, lowerValue[2], upperValue[2];
      int lowerColumn[2], upperColumn[2], lowerCount = 0, upperCount = 0;
      for (const auto& [col, val] : cols) {
        if (col == r - 1) {
          previous = val;
          previousHits += i == 0 || row[std::size_t(c - 1)] < 0;
        } else if (col == r + 1) {
          next = val;
        } else if (col < r) {
          lowerColumn[lowerCount] = col;
          lowerValue[lowerCount++] = val;
        } else {
          upperColumn[upperCount] = col;
          upperValue[upperCount++] = val;
        }
      }
      straight.setRow(r, diagonal, previous, next, lowerCount, lowerColumn, lowerValue, upperCount, upperColumn, upperValue);
      appendRow(A, cols, r, diagonal, nullptr);
    }
    if (g.keep < 1) {
      EXPECT_GT(previousHits, 0) << "the case the test is for did not arise";
    }
    std::vector<double> b(static_cast<std::size_t>(n)), guess(static_cast<std::size_t>(n));
    for (int e = 0; e < n; ++e) {
      b[std::size_t(e)] = u(rng) - 0.3;
      guess[std::size_t(e)] = u(rng);
    }
    std::vector<double> x1 = guess, x2 = guess;
    PressureSolver padded;
    const PressureSolver::Result r1 = padded.solve(A, b.data(), x1.data(), 1e-8, 1000);
    const PressureSolver::Result r2 = straight.solveRows(b.data(), x2.data(), 1e-8, 1000);
    EXPECT_TRUE(r1.converged);
    EXPECT_EQ(r1.iterations, r2.iterations) << g.nx << " x " << g.ny << " x " << g.nz;
    int differ = 0;
    for (int e = 0; e < n; ++e) differ += std::memcmp(&x1[std::size_t(e)], &x2[std::size_t(e)], sizeof(double)) != 0;
    EXPECT_EQ(differ, 0) << "of " << n << " unknowns, " << g.nx << " x " << g.ny << " x " << g.nz;
    // The same rows solved again (a second right-hand side needs no new startRows): the rows repacked to a
    // narrower width by the first solve (the one-slot plane 9 x 8 x 1) are not repacked a second time.
    std::vector<double> x3 = guess;
    const PressureSolver::Result r3 = straight.solveRows(b.data(), x3.data(), 1e-8, 1000);
    EXPECT_EQ(r3.iterations, r2.iterations) << "second solve, " << g.nx << " x " << g.ny << " x " << g.nz;
    int differAgain = 0;
    for (int e = 0; e < n; ++e) differAgain += std::memcmp(&x3[std::size_t(e)], &x2[std::size_t(e)], sizeof(double)) != 0;
    EXPECT_EQ(differAgain, 0) << "second solve, " << g.nx << " x " << g.ny << " x " << g.nz;
  }
}

TEST(VoxelDarcySolver, EachStepsPressureIsTheDirectSolutionOfItsSystem) {
  const VoxelMedium m = heterogeneous(25, 11);
  VoxelDarcyFilling filling(m);
  filling.setSource(Eigen::Vector3d::Zero(), 1.0e-3);
  filling.setViscosity(kMu);
  double worst = 0;
  for (int step = 0; step < 40; ++step) {
    std::vector<std::uint8_t> filled(m.count());
    for (std::size_t c = 0; c < m.count(); ++c) filled[c] = filling.filled(c);
    const std::vector<double> fill = filling.fill();
    filling.step(kQ, 0.2);
    std::vector<int> unknown;
    const Eigen::VectorXd direct = directPressure(m, filled, fill, filling.sourceVoxels(), kMu, kQ, unknown);
    if (direct.size() == 0) continue;
    double largest = direct.lpNorm<Eigen::Infinity>(), error = 0;
    for (std::size_t c = 0; c < m.count(); ++c)
      if (unknown[c] >= 0) error = std::max(error, std::abs(filling.pressure()[c] - direct[unknown[c]]));
    worst = std::max(worst, error / largest);
    ASSERT_LT(error, 1e-4 * largest) << "step " << step << ": " << direct.size() << " unknowns";
  }
  std::printf("each step's pressure against the direct solve: worst %.2e of the largest pressure (%zu filled voxels)\n",
              worst, filling.statistics().lastUnknowns);
}

// `small` (n^3) in the middle of a heterogeneous (3n)^3 region of more pore space, at the same positions.
VoxelMedium embedded(const VoxelMedium& small, unsigned seed) {
  const int n = small.size[0];
  VoxelMedium large = heterogeneous(3 * n, seed);
  for (std::size_t c = 0; c < small.count(); ++c) {
    const auto v = small.ijk(c);
    const std::size_t o = large.index(v[0] + n, v[1] + n, v[2] + n);
    large.porosity[o] = small.porosity[c];
    large.permeability[o] = small.permeability[c];
  }
  return large;
}

TEST(VoxelDarcySolver, ActiveSetBookkeepingAgreesWithDensePassesAndTheRegionDoesNotMatter) {
  // The same 21^3 medium alone and in the middle of a 63^3 region of more pore space that the cement never reaches.
  const VoxelMedium small = heterogeneous(21, 5);
  const VoxelMedium large = embedded(small, 6);
  VoxelDarcyFilling a(small), b(large);
  for (VoxelDarcyFilling* f : {&a, &b}) {
    f->setSource(Eigen::Vector3d::Zero(), 1.05e-3); // 2.1 voxels: no centre on the sphere, whatever the round-off
    f->setViscosity(kMu);
  }
  const double volume = 0.04e-6; // 40 mm^3: well inside the small region
  for (int step = 0; step < 100000 && a.time() < volume / kQ * (1 - 1e-12); ++step) {
    const double mu = step < 10 ? kMu : 2 * kMu; // a viscosity change on the way
    a.setViscosity(mu);
    b.setViscosity(mu);
    const double dt = std::min(volume / kQ - a.time(), 0.05);
    a.step(kQ, dt);
    b.step(kQ, dt);
    ASSERT_EQ(a.time(), b.time()) << "step " << step;
  }
  ASSERT_EQ(a.statistics().steps, b.statistics().steps);
  // Dense passes over every voxel of the small run.
  double dense = 0, worstFill = 0;
  int wet = 0;
  for (std::size_t c = 0; c < small.count(); ++c) {
    const auto v = small.ijk(c);
    const std::size_t o = large.index(v[0] + 21, v[1] + 21, v[2] + 21);
    const double f = a.fill()[c];
    dense += f * small.porosity[c] * small.voxelVolume();
    worstFill = std::max(worstFill, std::abs(f - b.fill()[o]));
    ASSERT_EQ(f > 0, a.arrivalTime()[c] >= 0) << "voxel " << c;
    if (f > 0) {
      ++wet;
      ASSERT_EQ(a.viscosity()[c], 2 * kMu) << "voxel " << c << " holds cement at the old viscosity";
      ASSERT_EQ(a.filled(c), b.filled(o));
    }
    // Nothing reached the small region's sides.
    if (v[0] == 0 || v[1] == 0 || v[2] == 0 || v[0] == 20 || v[1] == 20 || v[2] == 20) {
      ASSERT_EQ(f, 0.0);
    }
  }
  double outside = 0;
  for (std::size_t o = 0; o < large.count(); ++o) {
    const auto v = large.ijk(o);
    if (v[0] < 21 || v[1] < 21 || v[2] < 21 || v[0] >= 42 || v[1] >= 42 || v[2] >= 42) outside += b.fill()[o];
  }
  std::printf("active set: %d voxels with cement, fill differs by %.2e between the regions\n", wet, worstFill);
  EXPECT_GT(wet, 100);
  EXPECT_NEAR(a.cementVolume(), dense, 1e-12 * volume);
  EXPECT_NEAR(a.cementVolume(), volume, 1e-9 * volume);
  EXPECT_EQ(outside, 0.0);
  EXPECT_LT(worstFill, 1e-6);
  EXPECT_NEAR(a.sourcePressure(), b.sourcePressure(), 1e-6 * a.sourcePressure());
}

// Output times (stopAfter) end a call, not the step (issue 23: 1 s snapshots had added half again as many
// pressure solves at 10 ml). Oracle: the same filling without output times. Within a step the inflows are
// constant, so the run stopped at outputs takes the same steps; what may differ is only where a voxel's
// overshoot beyond full goes (at the output time instead of the step's end), which moves a few voxels' fill.
// A third run that ends its step at every output (the old way) shows the solves saved.
TEST(VoxelDarcySolver, OutputTimesDoNotAddPressureSolvesOrChangeTheFilling) {
  const VoxelMedium medium = heterogeneous(21, 7);
  VoxelDarcyFilling plain(medium), stopped(medium), shortened(medium);
  for (VoxelDarcyFilling* f : {&plain, &stopped, &shortened}) {
    f->setSource(Eigen::Vector3d::Zero(), 1.05e-3);
    f->setViscosity(kMu);
  }
  const double volume = 0.04e-6, T = volume / kQ, every = 0.0137; // outputs not a multiple of any step
  auto nextOutput = [&](double t) { return every * std::floor(t / every + 1 + 1e-9); };
  while (plain.time() < T * (1 - 1e-12)) plain.step(kQ, 0.05, T - plain.time());
  int calls = 0;
  while (stopped.time() < T * (1 - 1e-12)) {
    stopped.step(kQ, 0.05, std::min(T, nextOutput(stopped.time())) - stopped.time());
    ASSERT_NEAR(stopped.cementVolume(), stopped.injectedVolume(), 1e-9 * volume) << "call " << calls;
    ASSERT_LT(++calls, 100000);
  }
  while (shortened.time() < T * (1 - 1e-12))
    shortened.step(kQ, std::min({0.05, nextOutput(shortened.time()) - shortened.time(), T - shortened.time()}));
  const std::size_t solves = stopped.statistics().solves, plainSolves = plain.statistics().solves;
  std::printf("output times: %zu calls, %zu solves; without outputs %zu solves; steps ended at outputs %zu solves\n",
              stopped.statistics().steps, solves, plainSolves, shortened.statistics().solves);
  EXPECT_GT(stopped.statistics().steps, solves + 5); // outputs did stop calls inside steps
  // The same steps but for an overshoot's destination now and then: within 5 % of the plain run's solves,
  // and fewer than the run that ends its steps at outputs.
  EXPECT_LE(double(solves), 1.05 * double(plainSolves));
  EXPECT_GE(double(solves), 0.95 * double(plainSolves));
  EXPECT_LT(solves, shortened.statistics().solves);
  // The filling: the volume exactly, the tip pressure and the cement's voxels as the plain run's (0.5 %, and a
  // fill difference summed over the voxels of under 2 % of the cement's pore volume).
  EXPECT_NEAR(stopped.cementVolume(), volume, 1e-9 * volume);
  EXPECT_NEAR(stopped.sourcePressure(), plain.sourcePressure(), 5e-3 * plain.sourcePressure());
  double moved = 0, held = 0;
  for (std::size_t c = 0; c < medium.count(); ++c) {
    moved += std::abs(stopped.fill()[c] - plain.fill()[c]) * medium.porosity[c] * medium.voxelVolume();
    held += plain.fill()[c] * medium.porosity[c] * medium.voxelVolume();
  }
  std::printf("output times: fill moved %.3g %% of the cement; tip pressure %.6g Pa against %.6g Pa\n",
              100 * moved / held, stopped.sourcePressure(), plain.sourcePressure());
  EXPECT_LT(moved, 0.02 * held);
  // voxelState (the snapshots' one lookup) against the per-field accessors, every voxel: the same values.
  for (std::size_t c = 0; c < medium.count(); ++c) {
    const VoxelDarcyFilling::VoxelState s = stopped.voxelState(c);
    ASSERT_EQ(s.fill, stopped.fill()[c]) << "voxel " << c;
    ASSERT_EQ(s.pressure, stopped.pressure()[c]) << "voxel " << c;
    ASSERT_EQ(s.viscosity, stopped.viscosity()[c]) << "voxel " << c;
    ASSERT_EQ(s.arrival, stopped.arrivalTime()[c]) << "voxel " << c;
    ASSERT_EQ(s.darcyVelocity, stopped.darcyVelocity(c)) << "voxel " << c;
  }
}

TEST(VoxelBricks, IndexArithmeticAgreesWithDivisionAndNeighboursWithLookups) {
  // Sizes with an axis of one voxel (the inverse of 1 is the special case), not multiples of the brick's 8,
  // and one whose index needs all of 32 bits' reach in the last plane.
  for (const std::array<int, 3> size : {std::array<int, 3>{1, 1, 1}, {1, 7, 3}, {13, 1, 5}, {8, 8, 8}, {9, 17, 33},
                                        {1625, 1621, 1630}}) {
    VoxelBricks bricks;
    bricks.reset(size);
    const std::size_t nx = std::size_t(size[0]), ny = std::size_t(size[1]), n = nx * ny * std::size_t(size[2]);
    std::mt19937_64 rng(3);
    std::vector<std::size_t> probe;
    if (n <= 6000) {
      for (std::size_t c = 0; c < n; ++c) probe.push_back(c);
    } else {
      for (int t = 0; t < 200000; ++t) probe.push_back(rng() % n);
      for (std::size_t c : {std::size_t(0), nx - 1, nx, nx * ny - 1, nx * ny, n - 1}) probe.push_back(c);
    }
    for (std::size_t c : probe) {
      const auto v = bricks.ijk(c);
      ASSERT_EQ(v[0], int(c % nx)) << c;
      ASSERT_EQ(v[1], int(c / nx % ny)) << c;
      ASSERT_EQ(v[2], int(c / (nx * ny))) << c;
    }
    if (n > 6000) continue;
    for (std::size_t c = 0; c < n; ++c) ASSERT_EQ(bricks.find(c).brick, nullptr); // nothing allocated yet
    for (std::size_t c = 0; c < n; ++c) {
      const VoxelBricks::Cell t = bricks.touch(c, {}), f = bricks.find(c);
      ASSERT_EQ(t.brick, f.brick);
      ASSERT_EQ(t.local, f.local);
    }
    // Every voxel has its own (brick, place); each neighbour step lands on the neighbour's own.
    std::vector<std::pair<const void*, int>> seen;
    for (std::size_t c = 0; c < n; ++c) seen.push_back({bricks.find(c).brick, bricks.find(c).local});
    std::sort(seen.begin(), seen.end());
    ASSERT_EQ(std::unique(seen.begin(), seen.end()), seen.end());
    for (std::size_t c = 0; c < n; ++c) {
      const auto v = bricks.ijk(c);
      for (int a = 0; a < 3; ++a)
        for (int sign : {-1, 1}) {
          std::array<int, 3> w = v;
          w[std::size_t(a)] += sign;
          if (w[std::size_t(a)] < 0 || w[std::size_t(a)] >= size[std::size_t(a)]) continue;
          const VoxelBricks::Cell got = bricks.neighbour(bricks.find(c), v, a, sign);
          const VoxelBricks::Cell want = bricks.find(std::size_t(w[0]) + nx * (std::size_t(w[1]) + ny * std::size_t(w[2])));
          ASSERT_EQ(got.brick, want.brick);
          ASSERT_EQ(got.local, want.local);
        }
    }
    ASSERT_EQ(bricks.allocated(), std::size_t((size[0] + 7) / 8) * std::size_t((size[1] + 7) / 8) * std::size_t((size[2] + 7) / 8));
  }
}

TEST(VoxelDarcyFilling, MemoryFollowsTheCementNotTheRegion) {
  // The same 24^3 medium alone and in the middle of a 72^3 region (offset 24: the same brick boundaries).
  const VoxelMedium small = heterogeneous(24, 7);
  const VoxelMedium large = embedded(small, 8);
  VoxelDarcyFilling a(small), b(large);
  for (VoxelDarcyFilling* f : {&a, &b}) {
    f->setSource(Eigen::Vector3d::Zero(), 1.05e-3);
    f->setViscosity(kMu);
    inject(*f, kQ, 0.03e-6); // 30 mm^3
  }
  // The bricks the cement and its front touched, counted here: those holding a voxel with cement or an open
  // face neighbour of a filled voxel (the front of the next step; a front voxel is open).
  auto touched = [](const VoxelDarcyFilling& f, bool withFront) {
    const VoxelMedium& m = f.medium();
    std::vector<std::array<int, 3>> bricks;
    auto add = [&](int i, int j, int k) { bricks.push_back({i / 8, j / 8, k / 8}); };
    for (std::size_t c : f.wetVoxels()) {
      const auto v = m.ijk(c);
      add(v[0], v[1], v[2]);
      if (!withFront || !f.filled(c)) continue;
      for (int axis = 0; axis < 3; ++axis)
        for (int sign : {-1, 1}) {
          std::array<int, 3> w = v;
          w[std::size_t(axis)] += sign;
          if (w[std::size_t(axis)] < 0 || w[std::size_t(axis)] >= m.size[std::size_t(axis)]) continue;
          if (m.porosity[m.index(w[0], w[1], w[2])] > 0) add(w[0], w[1], w[2]);
        }
    }
    std::sort(bricks.begin(), bricks.end());
    return std::size_t(std::unique(bricks.begin(), bricks.end()) - bricks.begin());
  };
  const std::size_t lower = touched(b, false), upper = touched(b, true);
  std::printf("bricks: %zu (wet voxels' %zu, with the front %zu) in both regions; %zu kB against %zu kB of dense "
              "per-voxel arrays (51 bytes a voxel) over the 72^3 region\n",
              b.statistics().bricks, lower, upper, b.statistics().brickBytes / 1024, large.count() * 51 / 1024);
  EXPECT_GT(b.wetVoxels().size(), 100u);
  EXPECT_EQ(a.statistics().bricks, b.statistics().bricks);
  EXPECT_GE(b.statistics().bricks, lower);
  EXPECT_LE(b.statistics().bricks, upper);
  EXPECT_LT(double(b.statistics().brickBytes), 0.05 * double(large.count()) * 51.0);
}

} // namespace
} // namespace cementsph::voxeldarcy
