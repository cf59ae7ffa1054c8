#include "cementsph/sph/TipPressureProbe.h"

#include "cementsph/sph/Kernels.h"
#include "cementsph/sph/Simulation.h"

#include <Eigen/Geometry> // cross product

#include <cmath>
#include <stdexcept>

namespace cementsph::sph {

TipPressureProbe::TipPressureProbe(std::vector<Eigen::Vector3d> points, double startTime, double baselineWindow)
    : points_(std::move(points)), startTime_(startTime), baselineWindow_(baselineWindow) {
  if (points_.empty()) throw std::invalid_argument("tip pressure probe: needs at least one probe point");
  for (const auto& p : points_)
    if (!p.allFinite()) throw std::invalid_argument("tip pressure probe: probe point is not finite");
  if (!(std::isfinite(baselineWindow) && baselineWindow >= 0))
    throw std::invalid_argument("tip pressure probe: baseline window must be zero or positive");
}

std::vector<Eigen::Vector3d> TipPressureProbe::ringAroundTip(const Eigen::Vector3d& tip, const Eigen::Vector3d& direction,
                                                             double radius, int count, double axialOffset) {
  if (!(direction.norm() > 0) || count < 1 || !(radius >= 0))
    throw std::invalid_argument("tip pressure probe: ring needs a non-zero direction, count >= 1 and radius >= 0");
  const Eigen::Vector3d a = direction.normalized();
  Eigen::Index k;
  a.cwiseAbs().minCoeff(&k);
  const Eigen::Vector3d e1 = a.cross(Eigen::Vector3d::Unit(k)).normalized(), e2 = a.cross(e1);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < count; ++i) {
    const double phi = 2.0 * kPi * i / count;
    pts.push_back(tip + axialOffset * a + radius * (std::cos(phi) * e1 + std::sin(phi) * e2));
  }
  return pts;
}

namespace {
// Eq. 2 at a point: rho(x) = sum_j m_j W(x - x_j, h), over the fluid or the fixed particles.
double fluidDensityAt(const Simulation& sim, const Eigen::Vector3d& x) {
  const CubicSplineKernel W(sim.parameters().smoothingLength);
  const double s2 = W.support() * W.support();
  const FluidParticles& f = sim.fluid();
  double rho = 0;
  for (std::size_t j = 0; j < f.size(); ++j) {
    const double dx = x.x() - f.x[j], dy = x.y() - f.y[j], dz = x.z() - f.z[j];
    const double r2 = dx * dx + dy * dy + dz * dz;
    if (r2 < s2) rho += f.mass[j] * W.value(std::sqrt(r2));
  }
  return rho;
}

double fixedDensityAt(const Simulation& sim, const Eigen::Vector3d& x) {
  const CubicSplineKernel W(sim.parameters().smoothingLength);
  const double s2 = W.support() * W.support();
  const FixedParticles& s = sim.fixed();
  double rho = 0;
  for (std::size_t j = 0; j < s.size(); ++j) {
    const double dx = x.x() - s.x[j], dy = x.y() - s.y[j], dz = x.z() - s.z[j];
    const double r2 = dx * dx + dy * dy + dz * dz;
    if (r2 < s2) rho += static_cast<double>(s.mass[j]) * W.value(std::sqrt(r2));
  }
  return rho;
}
} // namespace

double TipPressureProbe::densityAt(const Simulation& sim, const Eigen::Vector3d& x) {
  return fluidDensityAt(sim, x) + fixedDensityAt(sim, x); // fluid and fixed particles alike (the paper)
}

double TipPressureProbe::pressureAt(const Simulation& sim, const Eigen::Vector3d& x) {
  return sim.parameters().pressure(densityAt(sim, x)); // Eq. 6
}

double TipPressureProbe::meanPressure(const Simulation& sim) const {
  const double h = sim.parameters().smoothingLength;
  if (fixedOwner_ != &sim || fixedCount_ != sim.fixed().size() || fixedH_ != h || fixedDensity_.size() != points_.size()) {
    fixedDensity_.clear();
    for (const auto& p : points_) fixedDensity_.push_back(fixedDensityAt(sim, p));
    fixedOwner_ = &sim;
    fixedCount_ = sim.fixed().size();
    fixedH_ = h;
  }
  double sum = 0;
  for (std::size_t k = 0; k < points_.size(); ++k)
    sum += sim.parameters().pressure(fluidDensityAt(sim, points_[k]) + fixedDensity_[k]); // Eq. 6
  return sum / double(points_.size());
}

PressureSample TipPressureProbe::sample(const Simulation& sim) {
  samples_.push_back({sim.time(), meanPressure(sim)});
  return samples_.back();
}

double TipPressureProbe::baseline() const {
  double sum = 0;
  std::size_t n = 0;
  for (const auto& s : samples_)
    if (s.time >= startTime_ && s.time <= startTime_ + baselineWindow_) {
      sum += s.meanPressure;
      ++n;
    }
  if (n == 0) throw std::logic_error("tip pressure probe: no sample in the baseline window (first 0.5 s)");
  return sum / double(n);
}

std::vector<PressureSample> TipPressureProbe::relativeSeries() const {
  const double b = baseline();
  std::vector<PressureSample> out = samples_;
  for (auto& s : out) s.meanPressure -= b;
  return out;
}

double TipPressureProbe::meanRelativePressure(double fromTime) const {
  const double b = baseline();
  double sum = 0;
  std::size_t n = 0;
  for (const auto& s : samples_)
    if (s.time >= fromTime) {
      sum += s.meanPressure - b;
      ++n;
    }
  if (n == 0) throw std::logic_error("tip pressure probe: no sample after the requested time");
  return sum / double(n);
}

} // namespace cementsph::sph
