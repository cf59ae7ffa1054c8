#include "cementsph/sph/CannulaEmitter.h"

#include "cementsph/sph/Kernels.h"
#include "cementsph/sph/Simulation.h"

#include <Eigen/Geometry> // cross product

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cementsph::sph {

namespace {
void requirePositive(double v, const char* what, const char* unit) {
  if (!(std::isfinite(v) && v > 0)) {
    std::ostringstream s;
    s << "cannula: " << what << " must be positive and finite, got " << v << " " << unit;
    throw std::invalid_argument(s.str());
  }
}

// Square-lattice points (spacing d, offset c d on both axes) strictly inside radius R.
std::vector<Eigen::Vector2d> discPoints(double R, double d, double c) {
  std::vector<Eigen::Vector2d> pts;
  const int n = static_cast<int>(std::ceil(R / d)) + 1;
  for (int j = -n; j <= n; ++j)
    for (int i = -n; i <= n; ++i) {
      const Eigen::Vector2d p((i + c) * d, (j + c) * d);
      if (p.norm() < R) pts.push_back(p);
    }
  return pts;
}
} // namespace

CannulaEmitter::CannulaEmitter(const CannulaSpec& spec) : spec_(spec) {
  requirePositive(spec.innerDiameter, "inner diameter D", "m");
  requirePositive(spec.flowRate, "flow rate Q", "m^3/s");
  requirePositive(spec.totalVolume, "total volume", "m^3");
  requirePositive(spec.spacing, "particle spacing d", "m");
  requirePositive(spec.restDensity, "rest density", "kg/m^3");
  if (!spec.tip.allFinite()) throw std::invalid_argument("cannula: tip position is not finite");
  if (!spec.direction.allFinite() || !(spec.direction.norm() > 0))
    throw std::invalid_argument("cannula: direction must be a non-zero finite vector");
  if (spec.buildWall) {
    if (!(std::isfinite(spec.wallLength) && spec.wallLength >= 0))
      throw std::invalid_argument("cannula: wall length must be zero or positive");
    if (spec.wallLayers < 0) throw std::invalid_argument("cannula: wall layer count must be zero or positive");
  }
  axis_ = spec.direction.normalized();
  // An orthonormal frame (e1, e2, axis): start from the coordinate axis least aligned with the cannula.
  Eigen::Index k;
  axis_.cwiseAbs().minCoeff(&k);
  e1_ = axis_.cross(Eigen::Vector3d::Unit(k)).normalized();
  e2_ = axis_.cross(e1_);

  const double d = spec.spacing, R = 0.5 * spec.innerDiameter;
  const double areaRatio = boreArea() / (d * d);
  std::vector<Eigen::Vector2d> centred = discPoints(R, d, 0.0), shifted = discPoints(R, d, 0.5);
  const bool useShifted = std::abs(double(shifted.size()) - areaRatio) < std::abs(double(centred.size()) - areaRatio);
  const std::vector<Eigen::Vector2d>& pts = useShifted ? shifted : centred; // centred always holds the axis point
  for (const Eigen::Vector2d& p : pts) pattern_.push_back(spec.tip + p.x() * e1_ + p.y() * e2_);

  const double n = spec.totalVolume / particleVolume();
  totalParticles_ = static_cast<std::size_t>(std::floor(n * (1.0 + 1e-12)));
  if (totalParticles_ == 0) throw std::invalid_argument("cannula: total volume is less than one particle volume d^3");
}

double CannulaEmitter::boreArea() const { return 0.25 * kPi * spec_.innerDiameter * spec_.innerDiameter; }

std::vector<Eigen::Vector3d> CannulaEmitter::wallPositions() const {
  std::vector<Eigen::Vector3d> out;
  if (!spec_.buildWall) return out;
  const double s = wallSpacing();
  const int axial = static_cast<int>(std::floor(spec_.wallLength / s + 1e-9));
  for (int k = 0; k < spec_.wallLayers; ++k) {
    const double radius = 0.5 * spec_.innerDiameter + 0.5 * s + k * s;
    const int around = std::max(6, static_cast<int>(std::lround(2.0 * kPi * radius / s)));
    for (int j = 0; j <= axial; ++j) {
      const Eigen::Vector3d centre = spec_.tip - (j * s) * axis_;
      const double twist = (j % 2) * 0.5; // stagger alternate rings by half a pitch
      for (int a = 0; a < around; ++a) {
        const double phi = 2.0 * kPi * (a + twist) / around;
        out.push_back(centre + radius * (std::cos(phi) * e1_ + std::sin(phi) * e2_));
      }
    }
  }
  // The bore behind the tip is solid (the cement column there is not simulated): square-lattice layers
  // reaching the first wall ring, from one fluid spacing behind the tip to the end of the wall.
  if (spec_.fillBore) {
    const std::vector<Eigen::Vector2d> disc = discPoints(0.5 * spec_.innerDiameter + 0.25 * s, s, 0.0);
    for (int j = 0; j * s <= spec_.wallLength - spec_.spacing + 1e-12; ++j)
      for (const Eigen::Vector2d& p : disc)
        out.push_back(spec_.tip - (spec_.spacing + j * s) * axis_ + p.x() * e1_ + p.y() * e2_);
  }
  return out;
}

std::size_t CannulaEmitter::addWall(Simulation& sim) const {
  std::size_t added = 0;
  for (const Eigen::Vector3d& p : wallPositions())
    if (sim.domain().contains(p)) {
      sim.addFixedParticle(p, wallParticleMass(), wallSpacing() * wallSpacing() * wallSpacing());
      ++added;
    }
  return added;
}

std::size_t CannulaEmitter::dueCount(double time) const {
  const double t = time - spec_.startTime;
  if (t < 0) return 0;
  // Particle k is due once Q t >= k d^3 (a relative 1e-12 absorbs round-off in t).
  const double k = std::floor(spec_.flowRate * t / particleVolume() * (1.0 + 1e-12));
  if (k >= double(totalParticles_)) return totalParticles_;
  return static_cast<std::size_t>(k) + 1;
}

std::size_t CannulaEmitter::emit(Simulation& sim) {
  const std::size_t due = dueCount(sim.time());
  const std::size_t before = emitted_;
  const Eigen::Vector3d velocity = exitSpeed() * axis_;
  for (; emitted_ < due; ++emitted_) {
    // Particle k was due at t_k = t0 + k d^3 / Q; it goes where it would be had it left its slot then at v0
    // (never more than one layer ahead). This keeps the position consistent with the exit speed whatever
    // the step, and keeps a layer from lying in one plane (with the overdamped integrator a planar layer in
    // empty space would stay planar: nothing pushes it off the plane).
    const double dueTime = spec_.startTime + double(emitted_) * particleInterval();
    const double ahead = std::min(exitSpeed() * std::max(0.0, sim.time() - dueTime), layerThickness());
    const Eigen::Vector3d p = pattern_[emitted_ % pattern_.size()] + ahead * axis_;
    ids_.push_back(sim.addFluidParticle(p, velocity, particleMass()));
  }
  return emitted_ - before;
}

} // namespace cementsph::sph
