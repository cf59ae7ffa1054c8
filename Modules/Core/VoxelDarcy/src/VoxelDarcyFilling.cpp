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
// The MIC(0) factor is made in the same pass over the rows (it reads the row's lower entries as the copy
// does): L D L^T with L = I + (strictly lower part of A) D^-1, pivot d_i = a_ii - sum over the lower
// neighbours k of a_ik^2 / d_k + tau a_ik (the rest of row k's upper part) / d_k, the dropped fill moved
// onto the diagonal (tau 0.97); a pivot below 0.25 a_ii (a nearly singular row) falls back to a_ii.
void PressureSolver::pad(const PressureSystem& A) {
  constexpr double tau = 0.97, safety = 0.25;
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
  for (std::vector<double>* v : {&pivot_, &inversePivot_, &previousScaled_, &nextScaled_, &upperSum_})
    v->resize(std::size_t(n)); // (kept from solve to solve: no fresh pages each step)
  for (int i = 0; i < n; ++i) {
    const int d = A.diagonal[std::size_t(i)];
    const double diagonal = A.value[std::size_t(d)];
    diagonalValue_[std::size_t(i)] = diagonal;
    double pivot = diagonal;
    std::size_t slot = std::size_t(i) * std::size_t(lowerWidth_);
    for (int e = A.rowStart[std::size_t(i)]; e < d; ++e) {
      const int j = A.column[std::size_t(e)];
      const double a = A.value[std::size_t(e)];
      pivot -= (a * a + tau * a * (upperSum_[std::size_t(j)] - a)) / pivot_[std::size_t(j)];
      if (j == i - 1) {
        previous_[std::size_t(i)] = a;
        continue;
      }
      lowerColumn_[slot] = j;
      lowerValue_[slot++] = a;
    }
    slot = std::size_t(i) * std::size_t(upperWidth_);
    double upper = 0;
    for (int e = d + 1; e < A.rowStart[std::size_t(i) + 1]; ++e) {
      const double a = A.value[std::size_t(e)];
      upper += a;
      if (A.column[std::size_t(e)] == i + 1) {
        next_[std::size_t(i)] = a;
        continue;
      }
      upperColumn_[slot] = A.column[std::size_t(e)];
      upperValue_[slot++] = a;
    }
    if (!(pivot >= safety * diagonal)) pivot = diagonal;
    pivot_[std::size_t(i)] = pivot;
    inversePivot_[std::size_t(i)] = 1.0 / pivot;
    previousScaled_[std::size_t(i)] = previous_[std::size_t(i)] / pivot;
    nextScaled_[std::size_t(i)] = next_[std::size_t(i)] / pivot;
    upperSum_[std::size_t(i)] = upper;
  }
}

template <int L, int U>
double PressureSolver::multiplyPadded(const double* x, double* y, int n) const {
  const int wl = L >= 0 ? L : lowerWidth_, wu = U >= 0 ? U : upperWidth_;
  const int* lc = lowerColumn_.data();
  const double* lv = lowerValue_.data();
  const int* uc = upperColumn_.data();
  const double* uv = upperValue_.data();
  const double* dv = diagonalValue_.data();
  const double* pv = previous_.data();
  const double* nv = next_.data();
  double xy = 0; // x . y, which CG needs next (one pass instead of two)
  for (int i = 0; i < n; ++i) {
    // x[n] is 0: the first row's "previous" and the last row's "next" read it with a zero coefficient.
    double sum = dv[i] * x[i] + pv[i] * x[i > 0 ? i - 1 : n] + nv[i] * x[i + 1];
    for (int e = 0; e < wl; ++e) sum += lv[i * wl + e] * x[lc[i * wl + e]];
    for (int e = 0; e < wu; ++e) sum += uv[i * wu + e] * x[uc[i * wu + e]];
    y[i] = sum;
    xy += x[i] * sum;
  }
  return xy;
}

// z = (L D L^T)^-1 r: forward sweep y_i = r_i - sum_k a_ik y_k / d_k (kept as q_i = y_i / d_i), then
// backward z_i = q_i - sum_j a_ij z_j / d_i over the upper neighbours. z[n] stays 0 (the empty slots').
// The forward sweep goes in the same pass as CG's update of x and r (x += alpha p, r -= alpha q, with
// |r|^2): row i's sweep needs r_i and the rows before it only. alpha 0 leaves x and r as they are.
template <int L, int U>
double PressureSolver::updateAndForward(double alpha, double* x, const double* p, double* r, const double* q, double* z,
                                        int n) const {
  const int wl = L >= 0 ? L : lowerWidth_;
  const int* lc = lowerColumn_.data();
  const double* lv = lowerValue_.data();
  const double* inverse = inversePivot_.data();
  const double* ps = previousScaled_.data();
  double chain = 0, r2 = 0; // chain: z of the row just done
  for (int i = 0; i < n; ++i) {
    x[i] += alpha * p[i];
    r[i] -= alpha * q[i];
    r2 += r[i] * r[i];
    double t = r[i];
    for (int e = 0; e < wl; ++e) t -= lv[i * wl + e] * z[lc[i * wl + e]];
    chain = t * inverse[i] - ps[i] * chain;
    z[i] = chain;
  }
  return r2;
}

template <int L, int U>
double PressureSolver::backward(const double* r, double* z, int n) const {
  const int wu = U >= 0 ? U : upperWidth_;
  const int* uc = upperColumn_.data();
  const double* uv = upperValue_.data();
  const double* inverse = inversePivot_.data();
  const double* ns = nextScaled_.data();
  double chain = 0;
  double rz = 0; // r . z, which CG needs next
  for (int i = n - 1; i >= 0; --i) {
    double t = 0;
    for (int e = 0; e < wu; ++e) t += uv[i * wu + e] * z[uc[i * wu + e]];
    chain = z[i] - t * inverse[i] - ns[i] * chain;
    z[i] = chain;
    rz += r[i] * chain;
  }
  return rz;
}

PressureSolver::Result PressureSolver::solve(const PressureSystem& A, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                             double tolerance, int maxIterations) {
  if (b.size() != A.rows())
    throw std::invalid_argument("voxel Darcy: the pressure system has " + std::to_string(A.rows()) +
                                " rows but its right-hand side " + std::to_string(b.size()) + " values");
  if (x.size() != A.rows()) x = Eigen::VectorXd::Zero(A.rows());
  return solve(A, b.data(), x.data(), tolerance, maxIterations);
}

PressureSolver::Result PressureSolver::solve(const PressureSystem& A, const double* b, double* x, double tolerance,
                                             int maxIterations) {
  pad(A);
  if (lowerWidth_ == 2 && upperWidth_ == 2) return run<2, 2>(A.rows(), b, x, tolerance, maxIterations); // the voxels' 7 points
  return run<-1, -1>(A.rows(), b, x, tolerance, maxIterations);
}

void PressureSolver::startRows(int n) {
  rows_ = n;
  rowsPacked_ = false;
  lowerWidth_ = upperWidth_ = 2;
  usedLower_ = usedUpper_ = 0;
  for (std::vector<double>* v : {&previous_, &next_, &diagonalValue_, &pivot_, &inversePivot_, &previousScaled_,
                                 &nextScaled_, &upperSum_})
    v->resize(std::size_t(n)); // (every entry written by setRow)
  lowerColumn_.resize(2 * std::size_t(n));
  upperColumn_.resize(2 * std::size_t(n));
  lowerValue_.resize(2 * std::size_t(n));
  upperValue_.resize(2 * std::size_t(n));
}

// As pad's pass over one row (an empty slot points at the vectors' zero entry n).
void PressureSolver::setRow(int i, double diagonal, double previous, double next, int lowerCount, const int* lowerColumn,
                            const double* lowerValue, int upperCount, const int* upperColumn, const double* upperValue) {
  constexpr double tau = 0.97, safety = 0.25;
  const std::size_t at = std::size_t(i);
  diagonalValue_[at] = diagonal;
  previous_[at] = previous;
  next_[at] = next;
  usedLower_ = std::max(usedLower_, lowerCount);
  usedUpper_ = std::max(usedUpper_, upperCount);
  double pivot = diagonal;
  for (int e = 0; e < 2; ++e) {
    const bool used = e < lowerCount;
    lowerColumn_[2 * at + std::size_t(e)] = used ? lowerColumn[e] : rows_;
    lowerValue_[2 * at + std::size_t(e)] = used ? lowerValue[e] : 0.0;
    if (!used) continue;
    const std::size_t j = std::size_t(lowerColumn[e]);
    const double a = lowerValue[e];
    pivot -= (a * a + tau * a * (upperSum_[j] - a)) / pivot_[j];
  }
  if (previous != 0) // (the last lower entry: column i - 1)
    pivot -= (previous * previous + tau * previous * (upperSum_[at - 1] - previous)) / pivot_[at - 1];
  double upper = 0;
  if (next != 0) upper += next; // (the first upper entry)
  for (int e = 0; e < 2; ++e) {
    const bool used = e < upperCount;
    upperColumn_[2 * at + std::size_t(e)] = used ? upperColumn[e] : rows_;
    upperValue_[2 * at + std::size_t(e)] = used ? upperValue[e] : 0.0;
    if (used) upper += upperValue[e];
  }
  if (!(pivot >= safety * diagonal)) pivot = diagonal;
  pivot_[at] = pivot;
  inversePivot_[at] = 1.0 / pivot;
  previousScaled_[at] = previous / pivot;
  nextScaled_[at] = next / pivot;
  upperSum_[at] = upper;
}

// As solve(PressureSystem): the padded width is the most slots a row uses (a small cement's first steps
// use fewer than two), the rows repacked to it in place (each row's slots move down, never over one not yet read).
PressureSolver::Result PressureSolver::solveRows(const double* b, double* x, double tolerance, int maxIterations) {
  if (usedLower_ == 2 && usedUpper_ == 2) return run<2, 2>(rows_, b, x, tolerance, maxIterations);
  // Once per startRows: a second solve of the same rows (another right-hand side) finds them packed already.
  for (std::size_t i = 0; i < std::size_t(rows_) && !rowsPacked_; ++i) {
    for (std::size_t e = 0; e < std::size_t(usedLower_); ++e) {
      lowerColumn_[i * std::size_t(usedLower_) + e] = lowerColumn_[2 * i + e];
      lowerValue_[i * std::size_t(usedLower_) + e] = lowerValue_[2 * i + e];
    }
    for (std::size_t e = 0; e < std::size_t(usedUpper_); ++e) {
      upperColumn_[i * std::size_t(usedUpper_) + e] = upperColumn_[2 * i + e];
      upperValue_[i * std::size_t(usedUpper_) + e] = upperValue_[2 * i + e];
    }
  }
  rowsPacked_ = true;
  lowerWidth_ = usedLower_;
  upperWidth_ = usedUpper_;
  return run<-1, -1>(rows_, b, x, tolerance, maxIterations);
}

// Preconditioned CG (as Eigen's ConjugateGradient), each iteration in four passes over the unknowns: the
// matrix product with p . Ap, the update of x and r with |r|^2, the two triangular sweeps with r . z, and
// the new direction. Its vectors are kept from solve to solve (std::vector: resized, not reallocated, as
// the cement grows; reallocating ~10 vectors a step cost a twentieth of a run in page faults).
template <int L, int U>
PressureSolver::Result PressureSolver::run(int n, const double* b, double* x, double tolerance, int maxIterations) {
  Result result;
  double rhsNorm2 = 0;
  for (int i = 0; i < n; ++i) rhsNorm2 += b[i] * b[i];
  if (rhsNorm2 == 0) {
    std::fill(x, x + n, 0.0);
    return result;
  }
  const double threshold = std::max(tolerance * tolerance * rhsNorm2, std::numeric_limits<double>::min());
  // Vectors of n + 1: entry n is the empty slots' zero.
  for (std::vector<double>* v : {&r_, &z_, &p_, &q_}) v->resize(std::size_t(n) + 1);
  double* r = r_.data();
  double* z = z_.data();
  double* p = p_.data();
  double* q = q_.data();
  r[n] = z[n] = p[n] = q[n] = 0;
  std::copy(x, x + n, p);
  multiplyPadded<L, U>(p, q, n);
  double r2 = 0;
  for (int i = 0; i < n; ++i) {
    r[i] = b[i] - q[i];
    r2 += r[i] * r[i];
  }
  if (r2 >= threshold) {
    updateAndForward<L, U>(0.0, x, p, r, q, z, n);
    double rz = backward<L, U>(r, z, n);
    std::copy(z, z + n, p);
    while (result.iterations < maxIterations) {
      const double alpha = rz / multiplyPadded<L, U>(p, q, n);
      r2 = updateAndForward<L, U>(alpha, x, p, r, q, z, n);
      ++result.iterations;
      if (r2 < threshold) break;
      const double rzOld = rz;
      rz = backward<L, U>(r, z, n);
      const double beta = rz / rzOld;
      for (int i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
    }
  }
  result.relativeResidual = std::sqrt(r2 / rhsNorm2);
  result.converged = r2 < threshold;
  return result;
}

void VoxelBricks::reset(const std::array<int, 3>& size) {
  size_ = size;
  inverseX_ = std::numeric_limits<std::uint64_t>::max() / std::uint64_t(size[0]) + 1;
  inverseY_ = std::numeric_limits<std::uint64_t>::max() / std::uint64_t(size[1]) + 1;
  bricksX_ = std::size_t((size[0] + kEdge - 1) >> kEdgeBits);
  bricksXY_ = bricksX_ * std::size_t((size[1] + kEdge - 1) >> kEdgeBits);
  directory_.assign(bricksXY_ * std::size_t((size[2] + kEdge - 1) >> kEdgeBits), -1);
  bricks_.clear();
  origin_.clear();
}

VoxelBricks::Cell VoxelBricks::touch(std::size_t c, const std::vector<double>& initialViscosity,
                                     const std::vector<float>* porosity) {
  const Cell found = find(c);
  if (found.brick) return found;
  const std::size_t nx = std::size_t(size_[0]), ny = std::size_t(size_[1]);
  const std::size_t i = c % nx, r = c / nx, j = r % ny, k = r / ny;
  std::int32_t& at = directory_[(k >> kEdgeBits) * bricksXY_ + (j >> kEdgeBits) * bricksX_ + (i >> kEdgeBits)];
  if (at < 0) {
    auto brick = std::make_unique<Brick>(); // every voxel at Voxel's initial values
    const std::array<int, 3> first{int(i & ~std::size_t(kEdge - 1)), int(j & ~std::size_t(kEdge - 1)),
                                   int(k & ~std::size_t(kEdge - 1))};
    at = std::int32_t(bricks_.size());
    bricks_.push_back(std::move(brick));
    origin_.push_back(first);
    // setVoxelViscosity's values and the impermeable voxels (the part of the brick inside the region)
    if (!initialViscosity.empty() || porosity)
      for (int local = 0; local < kVoxels; ++local) {
        const std::size_t vi = std::size_t(first[0]) + std::size_t(local & (kEdge - 1)),
                          vj = std::size_t(first[1]) + std::size_t((local >> kEdgeBits) & (kEdge - 1)),
                          vk = std::size_t(first[2]) + std::size_t(local >> (2 * kEdgeBits));
        if (vi >= nx || vj >= ny || vk >= std::size_t(size_[2])) continue;
        const std::size_t voxel = vi + nx * (vj + ny * vk);
        if (!initialViscosity.empty()) bricks_.back()->voxel[local].viscosity = initialViscosity[voxel];
        if (porosity && (*porosity)[voxel] <= 0) bricks_.back()->flags[local] = kClosedFlag;
      }
  }
  const int local = int(((k & (kEdge - 1)) << (2 * kEdgeBits)) | ((j & (kEdge - 1)) << kEdgeBits) | (i & (kEdge - 1)));
  return {bricks_[std::size_t(at)].get(), local};
}

VoxelDarcyFilling::VoxelDarcyFilling(VoxelMedium medium, FillingSettings settings)
    : medium_(std::move(medium)), settings_(settings) {
  const std::size_t n = medium_.count();
  for (int a = 0; a < 3; ++a)
    if (medium_.size[a] < 1 || !(medium_.spacing[a] > 0) || !std::isfinite(medium_.spacing[a]))
      throw std::invalid_argument("voxel Darcy: the grid needs at least one voxel and a positive spacing per axis");
  const bool uniformK = medium_.permeability.empty();
  if (medium_.porosity.size() != n || (!uniformK && medium_.permeability.size() != n))
    throw std::invalid_argument("voxel Darcy: porosity and permeability need one value per voxel");
  if (uniformK && (!(medium_.uniformPermeability > 0) || !std::isfinite(medium_.uniformPermeability)))
    throw std::invalid_argument("voxel Darcy: the uniform permeability " + std::to_string(medium_.uniformPermeability) +
                                " m^2 is not a positive number");
  if (!(settings_.maxFillPerStep > 0 && settings_.maxFillPerStep <= 1))
    throw std::invalid_argument("voxel Darcy: maxFillPerStep must be in (0, 1]");
  voxelVolume_ = medium_.voxelVolume();
  for (int a = 0; a < 3; ++a) {
    faceDistance_[std::size_t(a)] = medium_.spacing[a];
    faceArea_[std::size_t(a)] = voxelVolume_ / medium_.spacing[a];
  }
  // A voxel is closed (impermeable) where its porosity is 0, a pore voxel where it is above: state() reads it.
  // Checked in one branch-free pass (a count of bad voxels, vectorised), the first bad voxel named only when
  // there is one: a branch per voxel was a region-sized cost (issue 23).
  std::size_t bad = 0;
  const float* phiAt = medium_.porosity.data();
  for (std::size_t c = 0; c < n; ++c) bad += !(phiAt[c] >= 0.0f && phiAt[c] <= 1.0f);
  if (!uniformK) {
    const double* kAt = medium_.permeability.data();
    for (std::size_t c = 0; c < n; ++c) bad += phiAt[c] > 0.0f && !(kAt[c] > 0 && kAt[c] <= std::numeric_limits<double>::max());
  }
  for (std::size_t c = 0; bad && c < n; ++c) {
    const double phi = medium_.porosity[c], k = medium_.permeabilityAt(c);
    if (!(phi >= 0 && phi <= 1))
      throw std::invalid_argument("voxel Darcy: porosity " + std::to_string(phi) + " at voxel " + mm(medium_.centre(c)) +
                                  " is outside [0, 1]");
    if (phi > 0 && (!(k > 0) || !std::isfinite(k)))
      throw std::invalid_argument("voxel Darcy: permeability " + std::to_string(k) + " m^2 at the pore voxel " +
                                  mm(medium_.centre(c)) + " is not a positive number");
  }
  bricks_.reset(medium_.size);
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
    if (state(c) != kClosed) continue;
    pendingDt_ = 0; // the medium changed: the next step solves afresh
    frontStale_ = true; // and its front is searched afresh (the voxel may border the cement)
    medium_.porosity[c] = porosity[i]; // > 0: the voxel is a pore voxel from now on
    // A uniform medium stays one value while the opened voxel has it; another value makes it an array.
    if (medium_.permeability.empty() && permeability[i] != medium_.uniformPermeability)
      medium_.permeability.assign(medium_.count(), medium_.uniformPermeability);
    if (!medium_.permeability.empty()) medium_.permeability[c] = permeability[i];
    const VoxelBricks::Cell cell = bricks_.find(c);
    if (cell.brick) cell.set(VoxelBricks::kClosedFlag, false);
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
  if (state(own) == kClosed)
    throw std::invalid_argument("voxel Darcy: the outlet " + mm(centre) + " lies in an impermeable voxel");
  source_.clear();
  pendingDt_ = 0; // a new outlet: the next step solves afresh
  source_.push_back(own);
  const int r[3] = {int(std::ceil(radius / medium_.spacing[0])), int(std::ceil(radius / medium_.spacing[1])),
                    int(std::ceil(radius / medium_.spacing[2]))};
  for (int k = v[2] - r[2]; k <= v[2] + r[2]; ++k)
    for (int j = v[1] - r[1]; j <= v[1] + r[1]; ++j)
      for (int i = v[0] - r[0]; i <= v[0] + r[0]; ++i) {
        if (i < 0 || j < 0 || k < 0 || i >= medium_.size[0] || j >= medium_.size[1] || k >= medium_.size[2]) continue;
        const std::size_t c = medium_.index(i, j, k);
        if (c == own || state(c) == kClosed) continue;
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
  pendingDt_ = 0;
}

void VoxelDarcyFilling::setShearRateViscosity(std::function<double(double)> law, double flowIndex, int picard) {
  if (law && (!(flowIndex > 0) || picard < 1))
    throw std::invalid_argument("voxel Darcy: a shear-rate law needs a flow index > 0 and at least one iteration");
  shearLaw_ = std::move(law);
  frontStale_ = true;
  flowIndex_ = flowIndex;
  picardIterations_ = shearLaw_ ? picard : 1;
}

// Each filled voxel's viscosity at its Darcy-scale shear rate (the fluxes of the last solve); a voxel on
// the front takes the viscosity of the cement flowing into it (the largest inflow's upstream voxel).
void VoxelDarcyFilling::updateShearViscosity() {
  for (std::size_t c : filled_) {
    const double q = darcyVelocity(c).norm();
    const double mu = shearLaw_(rheology::darcyShearRate(q, medium_.permeabilityAt(c), medium_.porosity[c], flowIndex_));
    if (!(mu > 0) || !std::isfinite(mu))
      throw FillingError("voxel Darcy: the viscosity law gave " + std::to_string(mu) + " Pa s at " + mm(medium_.centre(c)));
    const VoxelBricks::Cell cell = touch(c);
    cell->viscosity = mu;
  }
  const int nx = medium_.size[0], ny = medium_.size[1];
  const std::ptrdiff_t stride[3] = {1, nx, std::ptrdiff_t(nx) * ny};
  for (std::size_t c : front_) {
    const VoxelBricks::Cell own = touch(c);
    const auto v = bricks_.ijk(c);
    double best = -1;
    for (int a = 0; a < 3; ++a)
      for (int sign : {-1, 1}) {
        const int coord = v[std::size_t(a)] + sign;
        if (coord < 0 || coord >= medium_.size[a]) continue;
        const std::size_t m = std::size_t(std::ptrdiff_t(c) + sign * stride[a]);
        const VoxelBricks::Cell cell = bricks_.find(m);
        if (state(m, cell) != kFilled) continue;
        const double inflow = std::abs(faceFlux(sign > 0 ? c : m, a));
        if (inflow > best) {
          best = inflow;
          own->viscosity = cell->viscosity;
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
    for (std::size_t c : *list) {
      const VoxelBricks::Cell cell = touch(c);
      cell->viscosity = mu;
    }
}

void VoxelDarcyFilling::setVoxelViscosity(std::vector<double> mu) {
  if (mu.size() != medium_.count()) throw std::invalid_argument("voxel Darcy: one viscosity per voxel");
  voxelViscosity_ = std::move(mu);
  pendingDt_ = 0;
  frontStale_ = true;
  bricks_.forEachVoxel([&](std::size_t c, VoxelBricks::Brick& b, int local) { b.voxel[local].viscosity = voxelViscosity_[c]; });
  uniformViscosity_ = false;
}

double VoxelDarcyFilling::cementVolume() const {
  double v = 0;
  for (std::size_t i = 0; i < wet_.size(); ++i) v += wetCell_[i]->fill * wetPoreVolume_[i];
  return v;
}

double VoxelDarcyFilling::sourcePressure() const {
  double sum = 0, w = 0;
  for (std::size_t c : source_) {
    const VoxelBricks::Cell cell = bricks_.find(c);
    if (state(c, cell) == kFilled) {
      sum += poreVolume(c) * cell->pressure;
      w += poreVolume(c);
    }
  }
  return w > 0 ? sum / w : settings_.frontPressurePa;
}

Eigen::Vector3d VoxelDarcyFilling::darcyVelocity(std::size_t c) const {
  const auto v = bricks_.ijk(c);
  const VoxelBricks::Cell own = bricks_.find(v[0], v[1], v[2]);
  if (!own.brick) return Eigen::Vector3d::Zero(); // the cement never came near: no flux was written there
  return darcyVelocityAt(own, v);
}

VoxelDarcyFilling::VoxelState VoxelDarcyFilling::voxelState(std::size_t c) const {
  VoxelState s;
  const auto v = bricks_.ijk(c);
  const VoxelBricks::Cell own = bricks_.find(v[0], v[1], v[2]);
  if (!own.brick) {
    if (!voxelViscosity_.empty()) s.viscosity = voxelViscosity_[c];
    return s;
  }
  const VoxelBricks::Voxel& x = *own.operator->();
  s.fill = x.fill;
  s.pressure = x.pressure;
  s.viscosity = x.viscosity;
  s.arrival = x.arrival;
  s.darcyVelocity = darcyVelocityAt(own, v);
  return s;
}

void VoxelDarcyFilling::markFilled(std::size_t c) {
  const VoxelBricks::Cell cell = touch(c);
  cell.set(VoxelBricks::kFilledFlag, 1);
  // A voxel barred on the front and then filled by another's excess: barred no longer (the flag is the
  // front's; left set, the assembly would leave out its faces from one side only).
  cell.set(VoxelBricks::kBarredFlag, 0);
  cell->fill = 1.0;
  cell->pressure = settings_.frontPressurePa; // warm start: the front's pressure, where it was
  if (uniformViscosity_ && !shearLaw_) cell->viscosity = viscosityValue_;
  newlyFilled_.push_back(c);
}

void VoxelDarcyFilling::wet(std::size_t c) {
  const VoxelBricks::Cell cell = touch(c);
  if (cell->arrival >= 0) return;
  cell->arrival = time_;
  wet_.push_back(c);
  wetCell_.push_back(cell);
  wetPoreVolume_.push_back(poreVolume(c)); // fixed from now on: only a closed voxel is ever opened (openVoxels)
  // (a shear-thinning run's front voxels already have their upstream viscosity)
  if (uniformViscosity_ && (!shearLaw_ || !cell.has(VoxelBricks::kInFrontFlag))) cell->viscosity = viscosityValue_;
}

// The front: every open pore voxel beside a filled one that is not filled itself. Kept from step to step
// (issue 23: a pass over the filled voxels each step was a thirtieth of a run): the front voxels filled
// since the last step leave it and the unfilled open neighbours of the voxels filled since join it, which
// is the same set as a search from every filled voxel, since a voxel never empties. A fresh search where
// the medium or the viscosity law changed (openVoxels opens new neighbours; a viscosity law resets the
// front's viscosities).
void VoxelDarcyFilling::findFront() {
  const bool uniform = uniformViscosity_ && !shearLaw_;
  const int nx = medium_.size[0], ny = medium_.size[1];
  const std::ptrdiff_t stride[3] = {1, nx, std::ptrdiff_t(nx) * ny};
  frontAdded_.clear();
  auto addNeighbours = [&](std::size_t c, const VoxelBricks::Cell& own, const std::array<int, 3>& v) {
    for (int a = 0; a < 3; ++a)
      for (int sign : {-1, 1}) {
        const int coord = v[std::size_t(a)] + sign;
        if (coord < 0 || coord >= medium_.size[a]) continue;
        const std::size_t m = std::size_t(std::ptrdiff_t(c) + sign * stride[a]);
        if (medium_.porosity[m] <= 0) continue; // closed
        VoxelBricks::Cell cell = bricks_.neighbour(own, v, a, sign);
        if (!cell.brick) cell = touch(m); // the front's state lives in bricks too
        if (cell.has(VoxelBricks::kFilledFlag) || cell.has(VoxelBricks::kInFrontFlag)) continue;
        cell.set(VoxelBricks::kInFrontFlag, 1);
        if (uniform) cell->viscosity = viscosityValue_;
        frontAdded_.push_back({m, cell});
      }
  };
  if (frontStale_ || !uniform) {
    for (const VoxelBricks::Cell& cell : frontCell_) cell.set(VoxelBricks::kInFrontFlag, 0);
    front_.clear();
    frontCell_.clear();
    for (std::size_t row = 0; row < filled_.size(); ++row) addNeighbours(filled_[row], filledCell_[row], filledIjk_[row]);
    frontStale_ = false;
  } else {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < front_.size(); ++i) {
      const VoxelBricks::Cell cell = frontCell_[i];
      if (cell.has(VoxelBricks::kFilledFlag)) {
        cell.set(VoxelBricks::kInFrontFlag, 0);
        continue;
      }
      front_[kept] = front_[i];
      frontCell_[kept++] = cell;
    }
    front_.resize(kept);
    frontCell_.resize(kept);
    for (std::size_t c : justFilled_) {
      const auto v = bricks_.ijk(c);
      addNeighbours(c, bricks_.find(v[0], v[1], v[2]), v);
    }
  }
  justFilled_.clear();
  // merged into front_ (in voxel order) and frontCell_ (alongside)
  std::sort(frontAdded_.begin(), frontAdded_.end(),
            [](const std::pair<std::size_t, VoxelBricks::Cell>& x, const std::pair<std::size_t, VoxelBricks::Cell>& y) {
              return x.first < y.first;
            });
  const std::size_t old = front_.size();
  front_.resize(old + frontAdded_.size());
  frontCell_.resize(front_.size());
  std::size_t a = old, b = frontAdded_.size(), out = front_.size();
  while (b > 0) { // from the back, in place
    if (a > 0 && front_[a - 1] > frontAdded_[b - 1].first) {
      --a;
      front_[--out] = front_[a];
      frontCell_[out] = frontCell_[a];
    } else {
      --b;
      front_[--out] = frontAdded_[b].first;
      frontCell_[out] = frontAdded_[b].second;
    }
  }
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
    const auto v = bricks_.ijk(c);
    const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& s : d) {
      const int i = v[0] + s[0], j = v[1] + s[1], k = v[2] + s[2];
      if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) continue;
      const std::size_t n = medium_.index(i, j, k);
      if (state(n) == kClosed || visited(n)) continue;
      seen.push_back(n);
      if (state(n) == kEmpty) {
        wet(n);
        const VoxelBricks::Cell cell = bricks_.find(n);
        double& voxelFill = cell->fill;
        const double room = (1.0 - voxelFill) * poreVolume(n);
        const double put = std::min(room, volume);
        voxelFill += put / poreVolume(n);
        volume -= put;
        if (voxelFill >= 1.0 - 1e-12) markFilled(n);
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
double VoxelDarcyFilling::step(double flowRate, double dtMax, double stopAfter) {
  if (source_.empty()) throw std::logic_error("voxel Darcy: setSource before step");
  if (!(dtMax > 0) || !(flowRate >= 0) || !(stopAfter > 0))
    throw std::invalid_argument("voxel Darcy: step needs dtMax > 0, stopAfter > 0, flow rate >= 0");
  // The rest of a step an output time cut short: the same inflows (the step is explicit in time), no solve.
  if (pendingDt_ > 0 && flowRate == pendingFlowRate_) {
    const double dt = std::min({pendingDt_, dtMax, stopAfter});
    pendingDt_ -= dt;
    if (pendingDt_ <= 1e-9 * dt) pendingDt_ = 0; // round-off of the output time's subtraction
    advanceFill(flowRate, dt);
    return dt;
  }
  pendingDt_ = 0;
  const auto t0 = Clock::now();
  const int nx = medium_.size[0], ny = medium_.size[1];
  const std::ptrdiff_t stride[3] = {1, nx, std::ptrdiff_t(nx) * ny};

  // Unknowns: the filled voxels, numbered in voxel order (so each row's columns come out sorted). The
  // voxels filled since the last step are merged into the sorted list; a voxel never empties again.
  // Each filled voxel's place in its brick goes along with it (filledCell_; bricks never move).
  if (!newlyFilled_.empty()) {
    std::sort(newlyFilled_.begin(), newlyFilled_.end());
    // (into buffers kept from step to step: no fresh pages to fault in each step)
    std::vector<std::size_t>& voxels = mergedVoxels_;
    std::vector<VoxelBricks::Cell>& cells = mergedCells_;
    std::vector<std::array<int, 3>>& ijk = mergedIjk_;
    voxels.resize(filled_.size() + newlyFilled_.size());
    cells.resize(voxels.size());
    ijk.resize(voxels.size());
    std::size_t a = 0, b = 0;
    for (std::size_t out = 0; out < voxels.size(); ++out)
      if (b == newlyFilled_.size() || (a < filled_.size() && filled_[a] < newlyFilled_[b])) {
        voxels[out] = filled_[a];
        ijk[out] = filledIjk_[a];
        cells[out] = filledCell_[a++];
      } else {
        voxels[out] = newlyFilled_[b++];
        ijk[out] = bricks_.ijk(voxels[out]);
        cells[out] = bricks_.find(ijk[out][0], ijk[out][1], ijk[out][2]);
      }
    filled_.swap(voxels);
    filledCell_.swap(cells);
    filledIjk_.swap(ijk);
    justFilled_.insert(justFilled_.end(), newlyFilled_.begin(), newlyFilled_.end()); // (findFront's)
    newlyFilled_.clear();
  }
  const int unknowns = int(filled_.size());
  for (int row = 0; row < unknowns; ++row) {
    const VoxelBricks::Cell& cell = filledCell_[std::size_t(row)];
    cell.unknown() = row;
  }
  findFront();

  // The source: spread over the filled outlet voxels by pore volume; while none is filled, the cement
  // goes straight into the outlet voxels.
  double filledSourcePore = 0, openSourcePore = 0;
  for (std::size_t c : source_) (state(c) == kFilled ? filledSourcePore : openSourcePore) += poreVolume(c);

  // Front links: (filled voxel, front voxel, transmissibility).
  struct Link { std::size_t from, to; double t; VoxelBricks::Cell fromCell, toCell; }; // (cells: no lookups later)
  std::vector<Link> links;
  links.reserve(front_.size() + 64);
  std::vector<double>& b = rhs_;
  std::vector<double>& x = solution_;
  b.resize(std::size_t(unknowns));
  x.resize(std::size_t(unknowns));
  const bool capillary = !entryPressure_.empty();
  auto frontPressure = [&](std::size_t m) {
    return settings_.frontPressurePa + (capillary ? double(entryPressure_[m]) : 0.0);
  };
  // The system for the current set of open front voxels (a front voxel barred by its capillary entry
  // pressure takes no flux: a no-flux face, as solid).
  auto assemble = [&]() {
    links.clear();
    std::fill(b.begin(), b.end(), 0.0);
    solver_.startRows(unknowns);
    // Each filled voxel's mobility once (a division), and each face between two filled voxels' transmissibility
    // once: the lower row computes it and keeps it (upperTransmissibility_, per row and axis), the upper row
    // (assembled later: rows go in voxel order) reads it back, and so do the face fluxes.
    rowMobility_.resize(std::size_t(unknowns));
    upperTransmissibility_.resize(3 * std::size_t(unknowns));
    double* rowMobility = rowMobility_.data();
    double* upperT = upperTransmissibility_.data();
    for (int row = 0; row < unknowns; ++row)
      rowMobility[row] = mobility(filled_[std::size_t(row)], filledCell_[std::size_t(row)]);
    for (int row = 0; row < unknowns; ++row) {
      const std::size_t c = filled_[std::size_t(row)];
      const VoxelBricks::Cell own = filledCell_[std::size_t(row)];
      x[std::size_t(row)] = own->pressure;
      const auto& v = filledIjk_[std::size_t(row)];
      const double lc = rowMobility[row];
      double diagonal = 0, previous = 0, next = 0;
      int lowerColumn[2], upperColumn[2], lowerCount = 0, upperCount = 0;
      double lowerValue[2], upperValue[2];
      // Neighbours in increasing voxel order: -z, -y, -x, (self), +x, +y, +z.
      for (int pass = 0; pass < 7; ++pass) {
        if (pass == 3) continue;
        const int axis = pass < 3 ? 2 - pass : pass - 4;
        const int sign = pass < 3 ? -1 : 1;
        const int coord = v[std::size_t(axis)] + sign;
        if (coord < 0 || coord >= medium_.size[axis]) continue;
        // An open neighbour of a filled voxel is filled or on the front: its brick is allocated (a closed
        // one's may not be).
        const VoxelBricks::Cell cell = bricks_.neighbour(own, v, axis, sign);
        if (!cell.brick || cell.has(VoxelBricks::kClosedFlag | VoxelBricks::kBarredFlag)) continue;
        const double area = faceArea_[std::size_t(axis)], dist = faceDistance_[std::size_t(axis)];
        if (cell.has(VoxelBricks::kFilledFlag)) {
          // The -x and +x neighbours, when filled, are the rows just before and after (rows in voxel
          // order): no read of their numbering.
          const int other = axis == 0 ? row + sign : cell.unknown();
          double t;
          if (sign < 0) {
            t = upperT[3 * other + axis]; // the lower row's
          } else {
            const double lm = rowMobility[other];
            t = area * 2.0 * lc * lm / ((lc + lm) * dist); // harmonic mean mobility
            upperT[3 * row + axis] = t;
          }
          diagonal += t;
          // (a -y or -z neighbour can be the row just before too, a +y or +z one the row just after: no
          // voxel with cement between them in voxel order; the solver keeps the coupling to rows i -+ 1 apart)
          if (other == row + sign) (sign < 0 ? previous : next) = -t;
          else if (sign < 0) {
            lowerColumn[lowerCount] = other;
            lowerValue[lowerCount++] = -t;
          } else {
            upperColumn[upperCount] = other;
            upperValue[upperCount++] = -t;
          }
        } else {
          // Ghost fluid: p_front at f of the way across the front voxel; half a voxel of this one's
          // mobility in series with f of the front voxel's.
          const std::size_t m = std::size_t(std::ptrdiff_t(c) + sign * stride[axis]);
          const double lm = mobility(m, cell);
          const double resistance = 0.5 * dist / lc + cell->fill * dist / lm;
          const double t = area / resistance;
          diagonal += t;
          b[std::size_t(row)] += t * frontPressure(m);
          links.push_back({c, m, t, own, cell});
        }
      }
      solver_.setRow(row, diagonal, previous, next, lowerCount, lowerColumn, lowerValue, upperCount, upperColumn, upperValue);
      if (filledSourcePore > 0 && c >= source_.front() && c <= source_.back() &&
          std::binary_search(source_.begin(), source_.end(), c))
        b[std::size_t(row)] += flowRate * poreVolume(c) / filledSourcePore;
    }
  };
  double solveSeconds = 0;
  auto solve = [&]() {
    const auto ts = Clock::now();
    const PressureSolver::Result r = solver_.solveRows(b.data(), x.data(), settings_.solverTolerance, settings_.maxSolverIterations);
    ++stats_.solves;
    stats_.iterations += std::size_t(r.iterations);
    stats_.worstResidual = std::max(stats_.worstResidual, r.relativeResidual);
    if (!r.converged) ++stats_.unconverged;
    if (!std::all_of(x.begin(), x.end(), [](double v) { return std::isfinite(v); }))
      throw FillingError("voxel Darcy: the pressure solve gave a non-finite value at t = " + std::to_string(time_) + " s");
    for (int row = 0; row < unknowns; ++row) {
      const VoxelBricks::Cell& cell = filledCell_[std::size_t(row)];
      cell->pressure = x[std::size_t(row)];
    }
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
    const auto v = bricks_.ijk(m);
    for (int a = 0; a < 3; ++a)
      for (int sign : {-1, 1}) {
        const int coord = v[std::size_t(a)] + sign;
        if (coord < 0 || coord >= medium_.size[a]) continue;
        const std::size_t c = std::size_t(std::ptrdiff_t(m) + sign * stride[a]);
        const VoxelBricks::Cell cell = bricks_.find(c);
        if (state(c, cell) == kFilled) up = std::max(up, cell->pressure);
      }
    return up;
  };
  // Face fluxes of the last solve (velocities, shear rates), signed along +axis; a front link's is its inflow.
  // Every face flux written before is on a voxel filled or on the front now (a filled voxel stays filled, a
  // front voxel stays on the front until it fills), so writing all three of each of those (0 where no flux
  // goes) leaves no stale value, without a list of the voxels written last time.
  auto faceFluxes = [&]() {
    for (std::size_t row = 0; row < filled_.size(); ++row) {
      const VoxelBricks::Cell own = filledCell_[row];
      const auto& v = filledIjk_[row];
      for (int a = 0; a < 3; ++a) {
        float flux = 0.0f; // (closed, the region's side, or on the front: the links below)
        if (v[std::size_t(a)] + 1 < medium_.size[a]) {
          const VoxelBricks::Cell cell = bricks_.neighbour(own, v, a, 1);
          if (cell.brick && cell.has(VoxelBricks::kFilledFlag)) // (a filled voxel is open)
            flux = float(upperTransmissibility_[3 * row + std::size_t(a)] * (own->pressure - cell->pressure));
        }
        own->faceFlux[a] = flux;
      }
    }
    for (const VoxelBricks::Cell& cell : frontCell_)
      for (int a = 0; a < 3; ++a) cell->faceFlux[a] = 0.0f;
    for (const Link& l : links) {
      const VoxelBricks::Cell& from = l.fromCell;
      const VoxelBricks::Cell& to = l.toCell;
      const double q = std::max(0.0, l.t * (from->pressure - frontPressure(l.to)));
      const std::ptrdiff_t d = std::ptrdiff_t(l.to) - std::ptrdiff_t(l.from);
      for (int a = 0; a < 3; ++a)
        if (d == stride[a]) from->faceFlux[a] = float(q);
        else if (d == -stride[a]) to->faceFlux[a] = float(-q);
    }
  };
  if (capillary)
    for (std::size_t m : front) {
      const VoxelBricks::Cell cell = bricks_.find(m);
      cell.set(VoxelBricks::kBarredFlag, upstreamPressure(m) <= frontPressure(m));
    }
  for (int pass = 0; pass < (unknowns > 0 ? picardIterations_ : 0); ++pass) {
    if (shearLaw_) updateShearViscosity();
    for (int round = 0;; ++round) {
      if (capillary && !front.empty()) {
        bool anyOpen = false;
        for (std::size_t m : front) anyOpen = anyOpen || !barredAt(m);
        if (!anyOpen) {
          std::size_t easiest = front.front();
          for (std::size_t m : front)
            if (upstreamPressure(m) - frontPressure(m) > upstreamPressure(easiest) - frontPressure(easiest)) easiest = m;
          setBarred(easiest, false);
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
        if (open == !barredAt(m)) continue;
        setBarred(m, !open);
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
    const VoxelBricks::Cell& from = l.fromCell;
    const double q = std::max(0.0, l.t * (from->pressure - frontPressure(l.to)));
    inflow.push_back({l.to, q});
  }
  // No outlet voxel filled yet (the start, or an outlet moved into fresh bone: VoxelDarcyInjection's second
  // tip): the cement goes straight into the outlet's voxels. Filled voxels elsewhere then have no source and
  // stand still (their pressure solves to the front's).
  if (filledSourcePore == 0)
    for (std::size_t c : source_)
      if (state(c) == kEmpty) inflow.push_back({c, flowRate * poreVolume(c) / openSourcePore});
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
    if (q > 0) dt = std::min(dt, std::max(1.0 - fill()[c], settings_.maxFillPerStep) * poreVolume(c) / q);
  if (!(dt > 0) || !std::isfinite(dt)) throw FillingError("voxel Darcy: no admissible step at t = " + std::to_string(time_) + " s");
  // The flux of the solve balances the source exactly (each row of the system is a voxel's balance), so the
  // inflow adds up to the flow rate; the remainder (round-off, the solver's tolerance) is spread so that
  // the cement volume stays the injected volume.
  double inflowSum = 0;
  for (const auto& e : inflow) inflowSum += e.second;
  const double scale = inflowSum > 0 ? flowRate / inflowSum : 0.0;
  inflow_.clear();
  for (const auto& [c, q] : inflow)
    if (q > 0) inflow_.push_back({c, q * scale});
  // Refused before anything moves: no half-step left pending, no time or volume advanced.
  if (flowRate > 0 && inflowSum <= 0)
    throw FillingError("voxel Darcy: the cement cannot enter the pore space at t = " + std::to_string(time_) + " s");
  const double taken = std::min(dt, stopAfter);
  pendingDt_ = dt - taken > 1e-9 * dt ? dt - taken : 0.0;
  pendingFlowRate_ = flowRate;
  advanceFill(flowRate, taken);
  return taken;
}

void VoxelDarcyFilling::advanceFill(double flowRate, double dt) {
  std::vector<std::pair<std::size_t, double>> excess;
  for (const auto& [c, q] : inflow_) {
    wet(c);
    const VoxelBricks::Cell cell = bricks_.find(c);
    // (filled already: by the part of this step before an output time, or by another voxel's excess)
    const bool wasFilled = cell.has(VoxelBricks::kFilledFlag);
    double& voxelFill = cell->fill;
    voxelFill += q * dt / poreVolume(c);
    if (voxelFill > 1.0) excess.push_back({c, (voxelFill - 1.0) * poreVolume(c)});
    if (voxelFill >= 1.0 - 1e-12) {
      if (wasFilled) voxelFill = 1.0;
      else markFilled(c);
    }
  }
  time_ += dt;
  injected_ += flowRate * dt;
  for (const auto& [c, e] : excess) depositExcess(c, e);
  ++stats_.steps;
  stats_.bricks = bricks_.allocated();
  stats_.brickBytes = bricks_.bytes();
}

} // namespace cementsph::voxeldarcy
