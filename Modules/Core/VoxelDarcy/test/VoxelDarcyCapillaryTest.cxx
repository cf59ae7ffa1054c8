// Oracles of the capillary entry in the voxel-grid Darcy filling (VoxelDarcyFilling::setEntryPressure; the
// physics and its parameters: VoxelDarcyInjectionModel.cpp's header), each against an exact solution:
//  * a column (1D) with a uniform entry pressure p_e: the tip pressure is the viscous Darcy drop over the cement
//    plus p_e, mu Q L / (k A) + p_e, L the cement's length from the outlet's centre. The two-point flux with the
//    ghost-fluid front is exact for the linear profile, so this holds to the solver's tolerance at every step;
//  * a ball with a uniform p_e: the front condition p = p_e is p - p_e = 0 shifted, so the fill is the one without
//    it and the tip pressure is mu Q / (4 pi k) (1.2 / a - 1 / R) + p_e, within the spherical oracle's 10 %
//    (VoxelDarcyFillingTest.cxx: a the outlet ball's radius);
//  * two channels fed from one outlet, a tight one (k_b, high p_e,b) and an open one (k_v, low p_e,v): each takes
//    Q_i = (p_tip - p_e,i) / R_i while that is positive, R_i = mu (h / (2 k_s) + x_i / k_i) / A (half the outlet
//    voxel and the cement's length x_i in the channel, in series), sum Q_i = Q. The tight channel opens when
//    Q R_v(x_v) reaches p_e,b - p_e,v, a closed form; after that the split follows from integrating the two
//    fronts (RK4 here, 20 000 steps). The split depends on the viscosity through the capillary number, at
//    50 and 400 Pa s; asserted within 1 % of the cement volume, the opening within the one step it can lag.
#include "cementsph/voxeldarcy/VoxelDarcyFilling.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>

namespace cementsph::voxeldarcy {
namespace {

constexpr double kPi = 3.14159265358979323846;

FillingSettings tight() {
  FillingSettings s;
  s.solverTolerance = 1e-12;
  return s;
}

// A column along x, one voxel across: the outlet in voxel 0, cement advancing to +x through a uniform medium with a
// uniform entry pressure. At every step the tip pressure of its solve (done on the fill the step started from, whose
// cement volume is V) is mu Q (V / (A phi) - h / 2) / (k A) + p_e: the cement fills from the outlet voxel's left
// face, so its front lies V / (A phi) from there and h/2 less from the outlet's centre.
TEST(VoxelDarcyCapillary, ColumnTipPressureIsTheViscousDropPlusTheEntryPressure) {
  const double h = 0.5e-3, phi = 0.4, k = 1e-9, pe = 5e4, Q = 1e-10, A = h * h;
  for (double mu : {50.0, 400.0}) {
    VoxelDarcyFilling filling(VoxelMedium::uniform({120, 1, 1}, Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(h),
                                                   phi, k),
                              tight());
    filling.setSource(Eigen::Vector3d::Zero(), 0.0);
    filling.setViscosity(mu);
    filling.setEntryPressure(std::vector<float>(filling.medium().count(), float(pe)));
    const double T = 60 * A * h * phi / Q; // 60 voxels of cement
    int checked = 0;
    while (filling.time() < T * (1 - 1e-12)) {
      const double before = filling.cementVolume();
      const bool outletFull = filling.filled(0);
      filling.step(Q, std::min(T - filling.time(), 0.01 * T));
      ASSERT_NEAR(filling.cementVolume(), filling.injectedVolume(), 1e-12 * T * Q);
      if (!outletFull) continue; // the first step fills the outlet voxel directly: no solve
      const double expected = mu * Q * (before / (A * phi) - 0.5 * h) / (k * A) + pe;
      ASSERT_NEAR(filling.sourcePressure() / expected, 1.0, 1e-6) << "mu " << mu << " at t = " << filling.time();
      ++checked;
    }
    EXPECT_GT(checked, 50);
  }
}

struct BallRun {
  double tip = 0, meanDistance = 0, a = 0;
  std::vector<double> fill;
};

BallRun ball(double pe) {
  const double h = 0.5e-3;
  VoxelDarcyFilling filling(VoxelMedium::uniform({41, 41, 41}, Eigen::Vector3d::Constant(-20 * h),
                                                 Eigen::Vector3d::Constant(h), 1.0, 1e-9),
                            tight());
  filling.setSource(Eigen::Vector3d::Zero(), 1.5e-3);
  filling.setViscosity(100.0);
  if (pe > 0) filling.setEntryPressure(std::vector<float>(filling.medium().count(), float(pe)));
  const double Q = 5e-8, T = 0.2e-6 / Q; // 0.2 ml
  while (filling.time() < T * (1 - 1e-12)) filling.step(Q, std::min(T - filling.time(), 0.05 * T));
  BallRun r;
  r.tip = filling.sourcePressure();
  r.fill = filling.fill();
  const VoxelMedium& m = filling.medium();
  double w = 0;
  for (std::size_t c = 0; c < m.count(); ++c) {
    r.meanDistance += filling.fill()[c] * m.centre(c).norm();
    w += filling.fill()[c];
  }
  r.meanDistance /= w;
  r.a = std::cbrt(3.0 * double(filling.sourceVoxels().size()) * m.voxelVolume() / (4 * kPi));
  return r;
}

TEST(VoxelDarcyCapillary, AUniformEntryPressureShiftsTheBallsPressureAndLeavesItsShape) {
  const double pe = 50e3; // of the order of the viscous tip pressure (about 140 kPa), so that the check means something
  const BallRun without = ball(0.0), with = ball(pe);
  const double R = std::cbrt(3 * 0.2e-6 / (4 * kPi));
  const double darcy = 100.0 * 5e-8 / (4 * kPi * 1e-9) * (1.2 / with.a - 1 / R);
  std::printf("ball: tip %.1f Pa with p_e %.0f Pa, %.1f Pa without; oracle %.1f Pa + p_e\n", with.tip, pe, without.tip,
              darcy);
  EXPECT_NEAR(with.tip / (darcy + pe), 1.0, 0.10);
  // The shift is exact: the same fill, and the tip pressure p_e above the run without (solver tolerance 1e-12).
  EXPECT_NEAR(with.tip - without.tip, pe, 1e-6 * with.tip);
  double worst = 0;
  for (std::size_t c = 0; c < with.fill.size(); ++c) worst = std::max(worst, std::abs(with.fill[c] - without.fill[c]));
  EXPECT_LT(worst, 1e-6);
}

// Two channels along x from an outlet voxel in the middle of a line: -x the tight one (bone), +x the open one (a
// vein). Returns the cement volume in the open channel over that in both, and the time the tight channel took its
// first cement.
struct Split {
  double openShare = 0, tightOpensAt = -1;
};

// kQ: the tight channel opens about 15 voxels into the open one at 50 Pa s, 1 voxel at 400 Pa s.
constexpr double kH = 0.5e-3, kA = kH * kH, kPhi = 0.5, kKs = 2e-9, kKb = 1e-9, kKv = 4e-9, kPeB = 2000, kPeV = 200,
                 kQ = 4.5e-12;
constexpr int kN = 401, kMid = 200;

Split simulated(double mu, double volume) {
  VoxelMedium m = VoxelMedium::uniform({kN, 1, 1}, Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(kH), kPhi, kKb);
  std::vector<float> pe(m.count());
  for (int i = 0; i < kN; ++i) {
    m.permeability[std::size_t(i)] = i < kMid ? kKb : i > kMid ? kKv : kKs;
    pe[std::size_t(i)] = float(i < kMid ? kPeB : i > kMid ? kPeV : 0.0);
  }
  FillingSettings settings = tight();
  settings.maxFillPerStep = 0.02;
  VoxelDarcyFilling filling(m, settings);
  filling.setSource(Eigen::Vector3d(kMid * kH, 0, 0), 0.0);
  filling.setViscosity(mu);
  filling.setEntryPressure(pe);
  const double T = volume / kQ;
  while (filling.time() < T * (1 - 1e-12)) filling.step(kQ, std::min(T - filling.time(), 1e-3 * T));
  double open = 0, tight = 0;
  for (int i = 0; i < kN; ++i) {
    const double v = filling.fill()[std::size_t(i)] * kPhi * m.voxelVolume(); // (the outlet voxel in neither)
    if (i > kMid) open += v;
    if (i < kMid) tight += v;
  }
  Split s;
  s.openShare = open / (open + tight);
  s.tightOpensAt = filling.arrivalTime()[std::size_t(kMid - 1)];
  return s;
}

// The oracle: fronts x_v, x_b from the outlet voxel's faces, from the time the outlet voxel is full.
Split oracle(double mu, double volume) {
  const double t0 = kA * kPhi * kH / kQ, T = volume / kQ;
  auto R = [mu](double x, double k) { return mu * (kH / (2 * kKs) + x / k) / kA; };
  // Closed form: the tight channel opens when Q R_v(x_v) = p_e,b - p_e,v, x_v = A phi (t - t0) Q / (A phi).
  const double xOpen = ((kPeB - kPeV) * kA / (kQ * mu) - kH / (2 * kKs)) * kKv;
  Split s;
  s.tightOpensAt = t0 + kA * kPhi * std::max(xOpen, 0.0) / kQ;
  auto rates = [&](const std::array<double, 2>& x) { // dx/dt of (open, tight)
    const double Rv = R(x[0], kKv), Rb = R(x[1], kKb);
    double p = (kQ + kPeV / Rv + kPeB / Rb) / (1 / Rv + 1 / Rb);
    if (p <= kPeB) p = kPeV + kQ * Rv; // the tight channel closed
    return std::array<double, 2>{std::max(0.0, (p - kPeV) / Rv) / (kA * kPhi),
                                 std::max(0.0, (p - kPeB) / Rb) / (kA * kPhi)};
  };
  std::array<double, 2> x{0, 0};
  const int n = 20000;
  const double dt = (T - t0) / n;
  for (int i = 0; i < n; ++i) {
    const auto k1 = rates(x);
    const auto k2 = rates({x[0] + 0.5 * dt * k1[0], x[1] + 0.5 * dt * k1[1]});
    const auto k3 = rates({x[0] + 0.5 * dt * k2[0], x[1] + 0.5 * dt * k2[1]});
    const auto k4 = rates({x[0] + dt * k3[0], x[1] + dt * k3[1]});
    for (std::size_t j = 0; j < 2; ++j) x[j] += dt / 6 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]);
  }
  s.openShare = x[0] / (x[0] + x[1]);
  return s;
}

TEST(VoxelDarcyCapillary, TwoChannelsSplitTheFlowByTheirEntryPressuresAndTheViscosity) {
  const double volume = 60 * kA * kPhi * kH; // 60 voxels of cement
  Split share[2];
  int i = 0;
  for (double mu : {50.0, 400.0}) {
    const Split sim = simulated(mu, volume), exact = oracle(mu, volume);
    std::printf("mu %.0f Pa s: open channel's share %.4f (oracle %.4f); tight opens at %.1f s (oracle %.1f s)\n",
                mu, sim.openShare, exact.openShare, sim.tightOpensAt, exact.tightOpensAt);
    EXPECT_NEAR(sim.openShare, exact.openShare, 0.01) << "mu " << mu;
    // The solve that opens it is the first after the crossing: later by at most one step (dtMax, 1e-3 T).
    EXPECT_GE(sim.tightOpensAt, exact.tightOpensAt - 1e-9 * volume / kQ) << "mu " << mu;
    EXPECT_LE(sim.tightOpensAt, exact.tightOpensAt + 1.01e-3 * volume / kQ) << "mu " << mu;
    share[i++] = sim;
  }
  // The capillary number decides: at 50 Pa s the open (low-entry) channel takes clearly more than at 400 Pa s.
  EXPECT_GT(share[0].openShare - share[1].openShare, 0.05);
}

} // namespace
} // namespace cementsph::voxeldarcy
