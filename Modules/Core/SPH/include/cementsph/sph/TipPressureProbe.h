// Injection pressure as the paper measured it in its simulations (Basafa et al. 2013, "Simulations"): "we
// estimated the SPH pressure at several points in the vicinity of the simulated cannula tip (Eq. 6) and took
// the average as the injection pressure. Mean pressure in the first 0.5 s of simulation was assumed as the
// 'zero' pressure and was subtracted from the subsequent values."
//
// At each probe point x the density is the Eq. 2 summation over fluid and fixed particles,
// rho(x) = sum_j m_j W(x - x_j, h) (cubic spline, Eq. 10, the simulation's h), and p = cs^2 (rho - rho0)
// (Eq. 6). A sample is the mean over the points. Brute force over the fluid particles (a handful of points
// per sample costs a few fluid-particle passes, less than a step); the fixed particles never move, so their
// share at each point is summed once and reused while the fixed set keeps its size.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace cementsph::sph {

class Simulation;

struct PressureSample {
  double time;         // [s] simulation time
  double meanPressure; // [Pa] mean of Eq. 6 over the probe points
};

class TipPressureProbe {
public:
  // Probe points (world, [m]); baseline window [s] after `startTime` (the paper: 0.5 s).
  explicit TipPressureProbe(std::vector<Eigen::Vector3d> points, double startTime = 0.0, double baselineWindow = 0.5);
  // `count` points evenly on a circle of `radius` about the axis, in the plane `axialOffset` ahead of the tip.
  static std::vector<Eigen::Vector3d> ringAroundTip(const Eigen::Vector3d& tip, const Eigen::Vector3d& direction,
                                                    double radius, int count = 6, double axialOffset = 0.0);

  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  // Eq. 2 density and Eq. 6 pressure at one point of the current state.
  static double densityAt(const Simulation& sim, const Eigen::Vector3d& x);
  static double pressureAt(const Simulation& sim, const Eigen::Vector3d& x);
  // Mean pressure over the probe points now [Pa] (not recorded).
  double meanPressure(const Simulation& sim) const;
  // Records (sim.time(), meanPressure) and returns the sample.
  PressureSample sample(const Simulation& sim);

  const std::vector<PressureSample>& samples() const { return samples_; }
  // Mean of the samples with startTime <= t <= startTime + baselineWindow. Throws std::logic_error if none.
  double baseline() const;
  // Samples minus the baseline (the paper's injection pressure).
  std::vector<PressureSample> relativeSeries() const;
  // Mean of the relative pressure over samples with t >= fromTime [s]. Throws std::logic_error if none.
  double meanRelativePressure(double fromTime) const;

private:
  std::vector<Eigen::Vector3d> points_;
  double startTime_, baselineWindow_;
  std::vector<PressureSample> samples_;
  // Fixed-particle share of Eq. 2 at each point, for the fixed set of this size and smoothing length.
  mutable std::vector<double> fixedDensity_;
  mutable std::size_t fixedCount_ = 0;
  mutable double fixedH_ = 0;
  mutable const void* fixedOwner_ = nullptr;
};

} // namespace cementsph::sph
