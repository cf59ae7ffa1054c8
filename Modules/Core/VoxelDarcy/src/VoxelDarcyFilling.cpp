#include "cementsph/voxeldarcy/VoxelDarcyFilling.h"

#include "cementsph/rheology/Rheology.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <sstream>

namespace cementsph::voxeldarcy {

namespace {
using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::string mm(const Eigen::Vector3d& p) {
  std::ostringstream s;
  s.precision(6);
  s << "(" << p.x() * 1e3 << ", " << p.y() * 1e3 << ", " << p.z() * 1e3 << ") mm";
  return s.str();
}
} // namespace

VoxelMedium VoxelMedium::uniform(std::array<int, 3> size, const Eigen::Vector3d& origin, const Eigen::Vector3d& spacing,
                                 double porosity, double permeability) {
  VoxelMedium m;
  m.size = size;
  m.origin = origin;
  m.spacing = spacing;
  m.porosity.assign(m.count(), float(porosity));
  m.permeability.assign(m.count(), permeability);
  return m;
}

void PressureSystem::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  const int n = rows();
  y.resize(n);
  const int* start = rowStart.data();
  const int* col = column.data();
  const double* val = value.data();
  for (int i = 0; i < n; ++i) {
    double sum = 0;
    for (int e = start[i]; e < start[i + 1]; ++e) sum += val[e] * x[col[e]];
    y[i] = sum;
  }
}

// The solver works on a padded copy of the matrix (ELLPACK: every row the same number of lower and upper
// slots, an empty slot pointing at the extra zero entry n of the vectors): fixed-length inner loops
// without unpredictable branches. The coupling to the row just before and just after (the voxel's -x and
// +x neighbours) is kept apart: in the triangular sweeps it is the chain each row waits on, and held in a
// register it costs one multiply-add per row instead of a store, a load and two operations.
void PressureSolver::pad(const PressureSystem& A) {
  const int n = A.rows();
  lowerWidth_ = upperWidth_ = 0;
  previous_.assign(std::size_t(n), 0.0);
  next_.assign(std::size_t(n), 0.0);
  for (int i = 0; i < n; ++i) {
    const int d = A.diagonal[std::size_t(i)];
    const bool hasPrevious = d > A.rowStart[std::size_t(i)] && A.column[std::size_t(d - 1)] == i - 1;
    const bool hasNext = d + 1 < A.rowStart[std::size_t(i) + 1] && A.column[std::size_t(d + 1)] == i + 1;
    lowerWidth_ = std::max(lowerWidth_, d - A.rowStart[std::size_t(i)] - int(hasPrevious));
    upperWidth_ = std::max(upperWidth_, A.rowStart[std::size_t(i) + 1] - d - 1 - int(hasNext));
  }
  lowerColumn_.assign(std::size_t(n) * std::size_t(lowerWidth_), n);
  lowerValue_.assign(lowerColumn_.size(), 0.0);
  upperColumn_.assign(std::size_t(n) * std::size_t(upperWidth_), n);
  upperValue_.assign(upperColumn_.size(), 0.0);
  diagonalValue_.resize(std::size_t(n));
  for (int i = 0; i < n; ++i) {
    const int d = A.diagonal[std::size_t(i)];
    diagonalValue_[std::size_t(i)] = A.value[std::size_t(d)];
    std::size_t slot = std::size_t(i) * std::size_t(lowerWidth_);
    for (int e = A.rowStart[std::size_t(i)]; e < d; ++e) {
      if (A.column[std::size_t(e)] == i - 1) {
        previous_[std::size_t(i)] = A.value[std::size_t(e)];
        continue;
      }
      lowerColumn_[slot] = A.column[std::size_t(e)];
      lowerValue_[slot++] = A.value[std::size_t(e)];
    }
    slot = std::size_t(i) * std::size_t(upperWidth_);
    for (int e = d + 1; e < A.rowStart[std::size_t(i) + 1]; ++e) {
      if (A.column[std::size_t(e)] == i + 1) {
        next_[std::size_t(i)] = A.value[std::size_t(e)];
        continue;
      }
      upperColumn_[slot] = A.column[std::size_t(e)];
      upperValue_[slot++] = A.value[std::size_t(e)];
    }
  }
}

template <int L, int U>
void PressureSolver::multiplyPadded(const double* x, double* y, int n) const {
  const int wl = L >= 0 ? L : lowerWidth_, wu = U >= 0 ? U : upperWidth_;
  const int* lc = lowerColumn_.data();
  const double* lv = lowerValue_.data();
  const int* uc = upperColumn_.data();
  const double* uv = upperValue_.data();
  const double* dv = diagonalValue_.data();
  const double* pv = previous_.data();
  const double* nv = next_.data();
  for (int i = 0; i < n; ++i) {
    // x[n] is 0: the first row's "previous" and the last row's "next" read it with a zero coefficient.
    double sum = dv[i] * x[i] + pv[i] * x[i > 0 ? i - 1 : n] + nv[i] * x[i + 1];
    for (int e = 0; e < wl; ++e) sum += lv[i * wl + e] * x[lc[i * wl + e]];
    for (int e = 0; e < wu; ++e) sum += uv[i * wu + e] * x[uc[i * wu + e]];
    y[i] = sum;
  }
}

// MIC(0) as L D L^T with L = I + (strictly lower part of A) D^-1: pivot d_i = a_ii - sum over the lower
// neighbours k of a_ik^2 / d_k + tau a_ik (the rest of row k's upper part) / d_k, the dropped fill moved
// onto the diagonal (tau 0.97); a pivot below 0.25 a_ii (a nearly singular row) falls back to a_ii.
void PressureSolver::factor(const PressureSystem& A) {
  constexpr double tau = 0.97, safety = 0.25;
  const int n = A.rows();
  pivot_.resize(n);
  inversePivot_.resize(n);
  previousScaled_.resize(n);
  nextScaled_.resize(n);
  upperSum_.resize(n);
  for (int i = 0; i < n; ++i) {
    const double diagonal = A.value[std::size_t(A.diagonal[std::size_t(i)])];
    double e = diagonal;
    for (int k = A.rowStart[std::size_t(i)]; k < A.diagonal[std::size_t(i)]; ++k) {
      const int j = A.column[std::size_t(k)];
      const double a = A.value[std::size_t(k)];
      e -= (a * a + tau * a * (upperSum_[j] - a)) / pivot_[j];
    }
    if (!(e >= safety * diagonal)) e = diagonal;
    pivot_[i] = e;
    inversePivot_[i] = 1.0 / e;
    previousScaled_[i] = previous_[std::size_t(i)] / e;
    nextScaled_[i] = next_[std::size_t(i)] / e;
    double upper = 0;
    for (int k = A.diagonal[std::size_t(i)] + 1; k < A.rowStart[std::size_t(i) + 1]; ++k) upper += A.value[std::size_t(k)];
    upperSum_[i] = upper;
  }
}

// z = (L D L^T)^-1 r: forward sweep y_i = r_i - sum_k a_ik y_k / d_k (kept as q_i = y_i / d_i), then
// backward z_i = q_i - sum_j a_ij z_j / d_i over the upper neighbours. z[n] stays 0 (the empty slots').
template <int L, int U>
void PressureSolver::preconditionPadded(const double* r, double* z, int n) const {
  const int wl = L >= 0 ? L : lowerWidth_, wu = U >= 0 ? U : upperWidth_;
  const int* lc = lowerColumn_.data();
  const double* lv = lowerValue_.data();
  const int* uc = upperColumn_.data();
  const double* uv = upperValue_.data();
  const double* inverse = inversePivot_.data();
  const double* ps = previousScaled_.data();
  const double* ns = nextScaled_.data();
  double chain = 0; // z of the row just done
  for (int i = 0; i < n; ++i) {
    double t = r[i];
    for (int e = 0; e < wl; ++e) t -= lv[i * wl + e] * z[lc[i * wl + e]];
    chain = t * inverse[i] - ps[i] * chain;
    z[i] = chain;
  }
  chain = 0;
  for (int i = n - 1; i >= 0; --i) {
    double t = 0;
    for (int e = 0; e < wu; ++e) t += uv[i * wu + e] * z[uc[i * wu + e]];
    chain = z[i] - t * inverse[i] - ns[i] * chain;
    z[i] = chain;
  }
}

PressureSolver::Result PressureSolver::solve(const PressureSystem& A, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                             double tolerance, int maxIterations) {
  pad(A);
  if (lowerWidth_ == 2 && upperWidth_ == 2) return run<2, 2>(A, b, x, tolerance, maxIterations); // the voxels' 7 points
  return run<-1, -1>(A, b, x, tolerance, maxIterations);
}

template <int L, int U>
PressureSolver::Result PressureSolver::run(const PressureSystem& A, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                           double tolerance, int maxIterations) {
  const int n = A.rows();
  Result result;
  if (x.size() != n) x = Eigen::VectorXd::Zero(n);
  const double rhsNorm2 = b.squaredNorm();
  if (rhsNorm2 == 0) {
    x.setZero();
    return result;
  }
  const double threshold = std::max(tolerance * tolerance * rhsNorm2, std::numeric_limits<double>::min());
  // Vectors of n + 1: entry n is the empty slots' zero.
  for (Eigen::VectorXd* v : {&r_, &z_, &p_, &q_}) v->setZero(n + 1);
  Eigen::VectorXd& xs = x;
  p_.head(n) = xs;
  multiplyPadded<L, U>(p_.data(), q_.data(), n);
  p_[n] = 0;
  auto head = [n](Eigen::VectorXd& v) { return v.head(n); };
  head(r_) = b - head(q_);
  double r2 = head(r_).squaredNorm();
  if (r2 >= threshold) {
    factor(A);
    preconditionPadded<L, U>(r_.data(), z_.data(), n);
    head(p_) = head(z_);
    double absNew = head(r_).dot(head(z_));
    while (result.iterations < maxIterations) {
      multiplyPadded<L, U>(p_.data(), q_.data(), n);
      const double alpha = absNew / head(p_).dot(head(q_));
      xs += alpha * head(p_);
      head(r_) -= alpha * head(q_);
      r2 = head(r_).squaredNorm();
      ++result.iterations;
      if (r2 < threshold) break;
      preconditionPadded<L, U>(r_.data(), z_.data(), n);
      const double absOld = absNew;
      absNew = head(r_).dot(head(z_));
      head(p_) = head(z_) + (absNew / absOld) * head(p_);
    }
  }
  result.relativeResidual = std::sqrt(r2 / rhsNorm2);
  result.converged = r2 < threshold;
  return result;
}

VoxelDarcyFilling::VoxelDarcyFilling(VoxelMedium medium, FillingSettings settings)
    : medium_(std::move(medium)), settings_(settings) {
  const std::size_t n = medium_.count();
  for (int a = 0; a < 3; ++a)
    if (medium_.size[a] < 1 || !(medium_.spacing[a] > 0) || !std::isfinite(medium_.spacing[a]))
      throw std::invalid_argument("voxel Darcy: the grid needs at least one voxel and a positive spacing per axis");
  if (medium_.porosity.size() != n || medium_.permeability.size() != n)
    throw std::invalid_argument("voxel Darcy: porosity and permeability need one value per voxel");
  if (!(settings_.maxFillPerStep > 0 && settings_.maxFillPerStep <= 1))
    throw std::invalid_argument("voxel Darcy: maxFillPerStep must be in (0, 1]");
  voxelVolume_ = medium_.voxelVolume();
  for (int a = 0; a < 3; ++a) {
    faceDistance_[std::size_t(a)] = medium_.spacing[a];
    faceArea_[std::size_t(a)] = voxelVolume_ / medium_.spacing[a];
  }
  state_.assign(n, kClosed);
  for (std::size_t c = 0; c < n; ++c) {
    const double phi = medium_.porosity[c], k = medium_.permeability[c];
    if (!(phi >= 0 && phi <= 1))
      throw std::invalid_argument("voxel Darcy: porosity " + std::to_string(phi) + " at voxel " + mm(medium_.centre(c)) +
                                  " is outside [0, 1]");
    if (phi > 0) {
      if (!(k > 0) || !std::isfinite(k))
        throw std::invalid_argument("voxel Darcy: permeability " + std::to_string(k) + " m^2 at the pore voxel " +
                                    mm(medium_.centre(c)) + " is not a positive number");
      state_[c] = kEmpty;
    }
  }
  fill_.assign(n, 0.0);
  pressure_.assign(n, 0.0);
  viscosity_.assign(n, 1.0);
  arrival_.assign(n, -1.0);
  faceFlux_.assign(3 * n, 0.0f);
  unknown_.assign(n, -1);
  barred_.assign(n, 0);
  inFront_.assign(n, 0);
}

void VoxelDarcyFilling::openVoxels(const std::vector<std::size_t>& voxels, const std::vector<float>& porosity,
                                   const std::vector<double>& permeability) {
  if (porosity.size() != voxels.size() || permeability.size() != voxels.size())
    throw std::invalid_argument("voxel Darcy: openVoxels needs one porosity and one permeability per voxel");
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    const std::size_t c = voxels[i];
    if (c >= medium_.count()) throw std::invalid_argument("voxel Darcy: openVoxels: a voxel outside the grid");
    if (!(porosity[i] > 0 && porosity[i] <= 1) || !(permeability[i] > 0) || !std::isfinite(permeability[i]))
      throw std::invalid_argument("voxel Darcy: openVoxels: porosity must be in (0, 1] and permeability > 0 at " +
                                  mm(medium_.centre(c)));
    if (state_[c] != kClosed) continue;
    medium_.porosity[c] = porosity[i];
    medium_.permeability[c] = permeability[i];
    state_[c] = kEmpty;
  }
}

void VoxelDarcyFilling::setSource(const Eigen::Vector3d& centre, double radius) {
  std::array<int, 3> v{};
  for (int a = 0; a < 3; ++a) {
    const double u = (centre[a] - medium_.origin[a]) / medium_.spacing[a];
    const long i = std::lround(u);
    if (!std::isfinite(u) || i < 0 || i >= medium_.size[a])
      throw std::invalid_argument("voxel Darcy: the outlet " + mm(centre) + " lies outside the grid");
    v[std::size_t(a)] = int(i);
  }
  const std::size_t own = medium_.index(v[0], v[1], v[2]);
  if (state_[own] == kClosed)
    throw std::invalid_argument("voxel Darcy: the outlet " + mm(centre) + " lies in an impermeable voxel");
  source_.clear();
  source_.push_back(own);
  const int r[3] = {int(std::ceil(radius / medium_.spacing[0])), int(std::ceil(radius / medium_.spacing[1])),
                    int(std::ceil(radius / medium_.spacing[2]))};
  for (int k = v[2] - r[2]; k <= v[2] + r[2]; ++k)
    for (int j = v[1] - r[1]; j <= v[1] + r[1]; ++j)
      for (int i = v[0] - r[0]; i <= v[0] + r[0]; ++i) {
        if (i < 0 || j < 0 || k < 0 || i >= medium_.size[0] || j >= medium_.size[1] || k >= medium_.size[2]) continue;
        const std::size_t c = medium_.index(i, j, k);
        if (c == own || state_[c] == kClosed) continue;
        if ((medium_.centre(c) - centre).norm() <= radius) source_.push_back(c);
      }
  std::sort(source_.begin(), source_.end());
}

void VoxelDarcyFilling::setEntryPressure(std::vector<float> entryPa) {
  if (!entryPa.empty() && entryPa.size() != medium_.count())
    throw std::invalid_argument("voxel Darcy: one entry pressure per voxel (or none)");
  for (float e : entryPa)
    if (!(e >= 0) || !std::isfinite(e)) throw std::invalid_argument("voxel Darcy: entry pressures must be finite and >= 0");
  entryPressure_ = std::move(entryPa);
}

void VoxelDarcyFilling::setShearRateViscosity(std::function<double(double)> law, double flowIndex, int picard) {
  if (law && (!(flowIndex > 0) || picard < 1))
    throw std::invalid_argument("voxel Darcy: a shear-rate law needs a flow index > 0 and at least one iteration");
  shearLaw_ = std::move(law);
  flowIndex_ = flowIndex;
  picardIterations_ = shearLaw_ ? picard : 1;
}

// Each filled voxel's viscosity at its Darcy-scale shear rate (the fluxes of the last solve); a voxel on
// the front takes the viscosity of the cement flowing into it (the largest inflow's upstream voxel).
void VoxelDarcyFilling::updateShearViscosity() {
  for (std::size_t c : filled_) {
    const double q = darcyVelocity(c).norm();
    const double mu = shearLaw_(rheology::darcyShearRate(q, medium_.permeability[c], medium_.porosity[c], flowIndex_));
    if (!(mu > 0) || !std::isfinite(mu))
      throw FillingError("voxel Darcy: the viscosity law gave " + std::to_string(mu) + " Pa s at " + mm(medium_.centre(c)));
    viscosity_[c] = mu;
  }
  const int nx = medium_.size[0], ny = medium_.size[1];
  const std::ptrdiff_t stride[3] = {1, nx, std::ptrdiff_t(nx) * ny};
  for (std::size_t c : front_) {
    const auto v = medium_.ijk(c);
    double best = -1;
    for (int a = 0; a < 3; ++a)
      for (int sign : {-1, 1}) {
        const int coord = v[std::size_t(a)] + sign;
        if (coord < 0 || coord >= medium_.size[a]) continue;
        const std::size_t m = std::size_t(std::ptrdiff_t(c) + sign * stride[a]);
        if (state_[m] != kFilled) continue;
        const double inflow = std::abs(faceFlux_[3 * (sign > 0 ? c : m) + std::size_t(a)]);
        if (inflow > best) {
          best = inflow;
          viscosity_[c] = viscosity_[m];
        }
      }
  }
}

// One value for every voxel: kept as that value, written only on the voxels the cement reaches (those
// with cement and the front now; the others as the cement reaches them: wet, markFilled, findFront).
void VoxelDarcyFilling::setViscosity(double mu) {
  if (!(mu > 0) || !std::isfinite(mu)) throw std::invalid_argument("voxel Darcy: viscosity must be a positive number");
  if (uniformViscosity_ && mu == viscosityValue_) return;
  uniformViscosity_ = true;
  viscosityValue_ = mu;
  for (const auto* list : {&filled_, &newlyFilled_, &front_, &wet_})
    for (std::size_t c : *list) viscosity_[c] = mu;
}

void VoxelDarcyFilling::setVoxelViscosity(std::vector<double> mu) {
  if (mu.size() != viscosity_.size()) throw std::invalid_argument("voxel Darcy: one viscosity per voxel");
  viscosity_ = std::move(mu);
  uniformViscosity_ = false;
}

double VoxelDarcyFilling::cementVolume() const {
  double v = 0;
  for (std::size_t c : wet_) v += fill_[c] * poreVolume(c);
  return v;
}

double VoxelDarcyFilling::sourcePressure() const {
  double sum = 0, w = 0;
  for (std::size_t c : source_)
    if (state_[c] == kFilled) {
      sum += poreVolume(c) * pressure_[c];
      w += poreVolume(c);
    }
  return w > 0 ? sum / w : settings_.frontPressurePa;
}

Eigen::Vector3d VoxelDarcyFilling::darcyVelocity(std::size_t c) const {
  const auto v = medium_.ijk(c);
  Eigen::Vector3d q;
  for (int a = 0; a < 3; ++a) {
    const double plus = faceFlux_[3 * c + std::size_t(a)];
    double minus = 0;
    if (v[std::size_t(a)] > 0) {
      const std::size_t stride = a == 0 ? 1 : a == 1 ? std::size_t(medium_.size[0])
                                                     : std::size_t(medium_.size[0]) * std::size_t(medium_.size[1]);
      minus = faceFlux_[3 * (c - stride) + std::size_t(a)];
    }
    q[a] = 0.5 * (plus + minus) / faceArea_[std::size_t(a)];
  }
  return q;
}

void VoxelDarcyFilling::markFilled(std::size_t c) {
  state_[c] = kFilled;
  fill_[c] = 1.0;
  pressure_[c] = settings_.frontPressurePa; // warm start: the front's pressure, where it was
  if (uniformViscosity_ && !shearLaw_) viscosity_[c] = viscosityValue_;
  newlyFilled_.push_back(c);
}

void VoxelDarcyFilling::wet(std::size_t c) {
  if (arrival_[c] >= 0) return;
  arrival_[c] = time_;
  wet_.push_back(c);
  // (a shear-thinning run's front voxels already have their upstream viscosity)
  if (uniformViscosity_ && (!shearLaw_ || !inFront_[c])) viscosity_[c] = viscosityValue_;
}

void VoxelDarcyFilling::findFront() {
  for (std::size_t c : front_) inFront_[c] = 0;
  front_.clear();
  const int nx = medium_.size[0], ny = medium_.size[1];
  const std::ptrdiff_t stride[3] = {1, nx, std::ptrdiff_t(nx) * ny};
  for (std::size_t c : filled_) {
    const auto v = medium_.ijk(c);
    for (int a = 0; a < 3; ++a)
      for (int sign : {-1, 1}) {
        const int coord = v[std::size_t(a)] + sign;
        if (coord < 0 || coord >= medium_.size[a]) continue;
        const std::size_t m = std::size_t(std::ptrdiff_t(c) + sign * stride[a]);
        if (state_[m] != kEmpty || inFront_[m]) continue;
        inFront_[m] = 1;
        front_.push_back(m);
      }
  }
  std::sort(front_.begin(), front_.end());
  if (uniformViscosity_ && !shearLaw_)
    for (std::size_t m : front_) viscosity_[m] = viscosityValue_;
}

// Volume beyond a voxel's pore volume moves on to the nearest unfilled pore voxels, reached through
// filled ones (breadth first), so the injected volume is kept exactly.
void VoxelDarcyFilling::depositExcess(std::size_t from, double volume) {
  const int nx = medium_.size[0], ny = medium_.size[1], nz = medium_.size[2];
  std::deque<std::size_t> queue{from};
  std::vector<std::size_t> seen{from};
  auto visited = [&](std::size_t c) { return std::find(seen.begin(), seen.end(), c) != seen.end(); };
  while (volume > 0 && !queue.empty()) {
    const std::size_t c = queue.front();
    queue.pop_front();
    const auto v = medium_.ijk(c);
    const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& s : d) {
      const int i = v[0] + s[0], j = v[1] + s[1], k = v[2] + s[2];
      if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) continue;
      const std::size_t n = medium_.index(i, j, k);
      if (state_[n] == kClosed || visited(n)) continue;
      seen.push_back(n);
      if (state_[n] == kEmpty) {
        const double room = (1.0 - fill_[n]) * poreVolume(n);
        const double put = std::min(room, volume);
        wet(n);
        fill_[n] += put / poreVolume(n);
        volume -= put;
        if (fill_[n] >= 1.0 - 1e-12) markFilled(n);
        if (volume <= 0) return;
      } else {
        queue.push_back(n);
      }
    }
  }
  if (volume > 1e-18)
    throw FillingError("voxel Darcy: the pore space connected to the outlet is full (" + std::to_string(volume * 1e9) +
                       " mm^3 had nowhere to go at t = " + std::to_string(time_) +
                       " s); enlarge roi_size_mm or inject less");
}

double VoxelDarcyFilling::step(double flowRate, double dtMax) {
  if (source_.empty()) throw std::logic_error("voxel Darcy: setSource before step");
  if (!(dtMax > 0) || !(flowRate >= 0)) throw std::invalid_argument("voxel Darcy: step needs dtMax > 0, flow rate >= 0");
  const auto t0 = Clock::now();
  const int nx = medium_.size[0], ny = medium_.size[1];
  const std::ptrdiff_t stride[3] = {1, nx, std::ptrdiff_t(nx) * ny};

  // Unknowns: the filled voxels, numbered in voxel order (so each row's columns come out sorted). The
  // voxels filled since the last step are merged into the sorted list; a voxel never empties again.
  if (!newlyFilled_.empty()) {
    std::sort(newlyFilled_.begin(), newlyFilled_.end());
    const std::size_t old = filled_.size();
    filled_.insert(filled_.end(), newlyFilled_.begin(), newlyFilled_.end());
    std::inplace_merge(filled_.begin(), filled_.begin() + std::ptrdiff_t(old), filled_.end());
    newlyFilled_.clear();
  }
  const int unknowns = int(filled_.size());
  for (int row = 0; row < unknowns; ++row) unknown_[filled_[std::size_t(row)]] = row;
  findFront();

  // The source: spread over the filled outlet voxels by pore volume; while none is filled, the cement
  // goes straight into the outlet voxels.
  double filledSourcePore = 0, openSourcePore = 0;
  for (std::size_t c : source_) (state_[c] == kFilled ? filledSourcePore : openSourcePore) += poreVolume(c);

  // Front links: (filled voxel, front voxel, transmissibility).
  struct Link { std::size_t from, to; double t; };
  std::vector<Link> links;
  links.reserve(front_.size() + 64);
  PressureSystem& A = system_;
  Eigen::VectorXd b(unknowns), x(unknowns);
  const bool capillary = !entryPressure_.empty();
  auto frontPressure = [&](std::size_t m) {
    return settings_.frontPressurePa + (capillary ? double(entryPressure_[m]) : 0.0);
  };
  // The system for the current set of open front voxels (a front voxel barred by its capillary entry
  // pressure takes no flux: a no-flux face, as solid).
  auto assemble = [&]() {
    links.clear();
    b.setZero();
    A.rowStart.resize(std::size_t(unknowns) + 1);
    A.diagonal.resize(std::size_t(unknowns));
    A.column.resize(std::size_t(unknowns) * 7);
    A.value.resize(std::size_t(unknowns) * 7);
    int* inner = A.column.data();
    double* value = A.value.data();
    int nnz = 0;
    for (int row = 0; row < unknowns; ++row) {
      const std::size_t c = filled_[std::size_t(row)];
      A.rowStart[std::size_t(row)] = nnz;
      x[row] = pressure_[c];
      const auto v = medium_.ijk(c);
      const double lc = mobility(c);
      double diagonal = 0;
      int diagonalAt = -1;
      // Neighbours in increasing voxel order: -z, -y, -x, (self), +x, +y, +z.
      for (int pass = 0; pass < 7; ++pass) {
        if (pass == 3) {
          diagonalAt = nnz;
          inner[nnz] = row;
          value[nnz++] = 0;
          continue;
        }
        const int axis = pass < 3 ? 2 - pass : pass - 4;
        const int sign = pass < 3 ? -1 : 1;
        const int coord = v[std::size_t(axis)] + sign;
        if (coord < 0 || coord >= medium_.size[axis]) continue;
        const std::size_t m = std::size_t(std::ptrdiff_t(c) + sign * stride[axis]);
        if (state_[m] == kClosed || barred_[m]) continue;
        const double area = faceArea_[std::size_t(axis)], dist = faceDistance_[std::size_t(axis)];
        const double lm = mobility(m);
        if (state_[m] == kFilled) {
          const double t = area * 2.0 * lc * lm / ((lc + lm) * dist); // harmonic mean mobility
          diagonal += t;
          inner[nnz] = unknown_[m];
          value[nnz++] = -t;
        } else {
          // Ghost fluid: p_front at f of the way across the front voxel; half a voxel of this one's
          // mobility in series with f of the front voxel's.
          const double resistance = 0.5 * dist / lc + fill_[m] * dist / lm;
          const double t = area / resistance;
          diagonal += t;
          b[row] += t * frontPressure(m);
          links.push_back({c, m, t});
        }
      }
      value[diagonalAt] = diagonal;
      A.diagonal[std::size_t(row)] = diagonalAt;
      if (filledSourcePore > 0 && std::binary_search(source_.begin(), source_.end(), c))
        b[row] += flowRate * poreVolume(c) / filledSourcePore;
    }
    A.rowStart[std::size_t(unknowns)] = nnz;
  };
  double solveSeconds = 0;
  auto solve = [&]() {
    const auto ts = Clock::now();
    const PressureSolver::Result r = solver_.solve(A, b, x, settings_.solverTolerance, settings_.maxSolverIterations);
    ++stats_.solves;
    stats_.iterations += std::size_t(r.iterations);
    stats_.worstResidual = std::max(stats_.worstResidual, r.relativeResidual);
    if (!r.converged) ++stats_.unconverged;
    if (!x.allFinite())
      throw FillingError("voxel Darcy: the pressure solve gave a non-finite value at t = " + std::to_string(time_) + " s");
    for (int row = 0; row < unknowns; ++row) pressure_[filled_[std::size_t(row)]] = x[row];
    solveSeconds += seconds(ts);
    stats_.solveSeconds += seconds(ts);
  };
  // Capillary entry: a front voxel takes cement only where the cement beside it is above its entry
  // pressure (Washburn/Young-Laplace, set by setEntryPressure). Which voxels are open is found by
  // solving with a guess, opening the barred voxels the solution pushes on and barring the open ones it
  // would drain (the complementarity conditions flux >= 0, p_up <= p_entry where barred), until nothing
  // changes; if every front voxel is barred, the easiest one opens (the pressure rises until it does).
  static const std::vector<std::size_t> none;
  const std::vector<std::size_t>& front = capillary && unknowns > 0 ? front_ : none;
  auto upstreamPressure = [&](std::size_t m) {
    double up = -std::numeric_limits<double>::infinity();
    const auto v = medium_.ijk(m);
    for (int a = 0; a < 3; ++a)
      for (int sign : {-1, 1}) {
        const int coord = v[std::size_t(a)] + sign;
        if (coord < 0 || coord >= medium_.size[a]) continue;
        const std::size_t c = std::size_t(std::ptrdiff_t(m) + sign * stride[a]);
        if (state_[c] == kFilled) up = std::max(up, pressure_[c]);
      }
    return up;
  };
  // Face fluxes of the last solve (velocities, shear rates), signed along +axis; a front link's is its inflow.
  auto faceFluxes = [&]() {
    for (std::size_t c : fluxWritten_)
      for (int a = 0; a < 3; ++a) faceFlux_[3 * c + std::size_t(a)] = 0.0f;
    fluxWritten_ = filled_;
    fluxWritten_.insert(fluxWritten_.end(), front_.begin(), front_.end());
    for (std::size_t c : filled_) {
      const auto v = medium_.ijk(c);
      for (int a = 0; a < 3; ++a) {
        if (v[std::size_t(a)] + 1 >= medium_.size[a]) continue;
        const std::size_t m = c + std::size_t(stride[a]);
        if (state_[m] != kFilled) continue;
        const double lc = mobility(c), lm = mobility(m);
        const double t = faceArea_[std::size_t(a)] * 2.0 * lc * lm / ((lc + lm) * faceDistance_[std::size_t(a)]);
        faceFlux_[3 * c + std::size_t(a)] = float(t * (pressure_[c] - pressure_[m]));
      }
    }
    for (const Link& l : links) {
      const double q = std::max(0.0, l.t * (pressure_[l.from] - frontPressure(l.to)));
      const std::ptrdiff_t d = std::ptrdiff_t(l.to) - std::ptrdiff_t(l.from);
      for (int a = 0; a < 3; ++a)
        if (d == stride[a]) faceFlux_[3 * l.from + std::size_t(a)] = float(q);
        else if (d == -stride[a]) faceFlux_[3 * l.to + std::size_t(a)] = float(-q);
    }
  };
  if (capillary)
    for (std::size_t m : front) barred_[m] = upstreamPressure(m) <= frontPressure(m);
  for (int pass = 0; pass < (unknowns > 0 ? picardIterations_ : 0); ++pass) {
    if (shearLaw_) updateShearViscosity();
    for (int round = 0;; ++round) {
      if (capillary && !front.empty()) {
        bool anyOpen = false;
        for (std::size_t m : front) anyOpen = anyOpen || !barred_[m];
        if (!anyOpen) {
          std::size_t easiest = front.front();
          for (std::size_t m : front)
            if (upstreamPressure(m) - frontPressure(m) > upstreamPressure(easiest) - frontPressure(easiest)) easiest = m;
          barred_[easiest] = 0;
        }
      }
      assemble();
      if (links.empty())
        throw FillingError("voxel Darcy: the pore space connected to the outlet is full at t = " + std::to_string(time_) +
                           " s (no unfilled pore voxel borders the cement); enlarge roi_size_mm or inject less");
      solve();
      if (!capillary) break;
      bool changed = false;
      for (std::size_t m : front) {
        const bool open = upstreamPressure(m) > frontPressure(m);
        if (open == !barred_[m]) continue;
        barred_[m] = !open;
        changed = true;
      }
      ++stats_.capillaryRounds;
      if (!changed || round >= 50) break;
    }
    if (shearLaw_) faceFluxes();
  }
  stats_.assemblySeconds += seconds(t0) - solveSeconds;
  stats_.lastUnknowns = std::size_t(unknowns);

  faceFluxes();
  std::vector<std::pair<std::size_t, double>> inflow; // front voxel, m^3/s
  inflow.reserve(links.size());
  for (const Link& l : links) {
    const double q = std::max(0.0, l.t * (pressure_[l.from] - frontPressure(l.to)));
    inflow.push_back({l.to, q});
  }
  // No outlet voxel filled yet (the start, or an outlet moved into fresh bone: VoxelDarcyInjection's second
  // tip): the cement goes straight into the outlet's voxels. Filled voxels elsewhere then have no source and
  // stand still (their pressure solves to the front's).
  if (filledSourcePore == 0)
    for (std::size_t c : source_)
      if (state_[c] == kEmpty) inflow.push_back({c, flowRate * poreVolume(c) / openSourcePore});
  std::sort(inflow.begin(), inflow.end());
  std::size_t merged = 0; // one entry per front voxel
  for (std::size_t i = 0; i < inflow.size(); ++i) {
    if (merged > 0 && inflow[merged - 1].first == inflow[i].first) inflow[merged - 1].second += inflow[i].second;
    else inflow[merged++] = inflow[i];
  }
  inflow.resize(merged);
  stats_.lastFrontVoxels = merged;

  // The step: no voxel overshoots full by more than maxFillPerStep of its pore volume.
  double dt = dtMax;
  for (const auto& [c, q] : inflow)
    if (q > 0) dt = std::min(dt, std::max(1.0 - fill_[c], settings_.maxFillPerStep) * poreVolume(c) / q);
  if (!(dt > 0) || !std::isfinite(dt)) throw FillingError("voxel Darcy: no admissible step at t = " + std::to_string(time_) + " s");
  // The flux of the solve balances the source exactly (each row of the system is a voxel's balance), so the
  // inflow adds up to the flow rate; the remainder (round-off, the solver's tolerance) is spread so that
  // the cement volume stays the injected volume.
  double inflowSum = 0;
  for (const auto& e : inflow) inflowSum += e.second;
  const double scale = inflowSum > 0 ? flowRate / inflowSum : 0.0;
  std::vector<std::pair<std::size_t, double>> excess;
  inflow_.clear();
  for (const auto& [c, q] : inflow) {
    if (q <= 0) continue;
    inflow_.push_back({c, q * scale});
    wet(c);
    fill_[c] += q * scale * dt / poreVolume(c);
    if (fill_[c] > 1.0) excess.push_back({c, (fill_[c] - 1.0) * poreVolume(c)});
    if (fill_[c] >= 1.0 - 1e-12) markFilled(c);
  }
  time_ += dt;
  injected_ += flowRate * dt;
  if (flowRate > 0 && inflowSum <= 0)
    throw FillingError("voxel Darcy: the cement cannot enter the pore space at t = " + std::to_string(time_) + " s");
  for (const auto& [c, e] : excess) depositExcess(c, e);
  ++stats_.steps;
  return dt;
}

} // namespace cementsph::voxeldarcy
