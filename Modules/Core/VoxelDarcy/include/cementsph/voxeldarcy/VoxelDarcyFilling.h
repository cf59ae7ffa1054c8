// Incompressible Darcy filling on the CT's voxel grid: the pressure of the creeping cement is solved on
// the voxels it fills, and the cement advances voxel by voxel into the pore space (a volume-of-fluid
// filling scheme, as in the control-volume mould-filling method of Bruschke & Advani 1990, Polym. Compos.
// 11:398). The issue "Physical cement" allows the pressure on the voxel grid in place of the particles'
// Poisson equation where it measures better; VALIDATION.md has the figures for both.
//
// Model (assumptions and regime, docs/architecture.md):
//  * Creeping flow (Re << 1, inertia dropped) of an incompressible cement through a rigid porous medium,
//    Darcy's law q = -(k / mu) grad p for the superficial velocity q [m/s]; div q = s (the cannula's
//    outflow, a uniform volume source over the pore voxels within `sourceRadius` of the outlet).
//  * Each voxel has a porosity phi (pore volume fraction; 0 = impermeable: solid, cortex) and a
//    permeability k [m^2]; a pore-resolved CT gives phi = 1 in pore voxels and 0 in solid ones, a clinical
//    CT a continuum phi and k from HU.
//  * The displaced fluid (marrow, or air/water in foam) is at the front's pressure p_front, 0 Pa gauge by
//    default (its own viscosity neglected: cement/marrow viscosity ratio >> 1). Optionally each voxel has a
//    capillary entry pressure the cement must exceed to enter it (setEntryPressure).
//  * Each voxel's fill f in [0, 1] is the fraction of its pore volume that holds cement. A voxel is
//    filled at f = 1: its pressure is an unknown. A pore voxel beside a filled one with f < 1 is on the
//    front: the cement's edge in it lies f of the way across it, where p = p_front (a ghost-fluid
//    Dirichlet condition, Gibou et al. 2002 J Comput Phys 176:205, so the front sits between voxel centres
//    and the pressure is second-order accurate up to it).
//  * Two-point flux between voxel centres with the harmonic mean of the mobilities k / mu (no flux into
//    phi = 0 voxels or across the region's sides).
//  * One step: solve the pressure (a symmetric positive definite system, a conjugate gradient with a
//    modified incomplete Cholesky MIC(0) preconditioner, warm-started: PressureSolver below), compute the
//    flux into each front voxel, choose dt so that no voxel gains more than `maxFillPerStep` of its pore
//    volume beyond full, fill, and pass any excess on to the nearest unfilled pore voxels. The injected
//    volume is kept exactly (to round-off).
//  * Cost scales with the cement, not the region (issue 23): every per-step pass (numbering, assembly,
//    front search, fluxes, volume sum, viscosity update) runs over the filled voxels and their front only
//    (lists kept as the cement grows), and the per-voxel state (fill, pressure, viscosity, arrival time,
//    face fluxes, numbering) lives in bricks of 8^3 voxels allocated when the cement first comes next to
//    them (VoxelBricks), so its memory follows the cement too. What remains in proportion to the region:
//    the constructor's check of the medium, the medium itself (the caller's), a brick directory of 4 bytes
//    per 512 voxels, and a caller's own dense copy of an accessor (operator std::vector).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace cementsph::voxeldarcy {

// The medium on an axis-aligned voxel grid. Coordinates: the CT's patient frame in metres; voxel (i, j, k)
// has its centre at origin + spacing .* (i, j, k).
struct VoxelMedium {
  std::array<int, 3> size{0, 0, 0};
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones();
  std::vector<float> porosity;      // per voxel, 0 = impermeable
  std::vector<double> permeability; // per voxel [m^2] (ignored where porosity is 0); or empty: uniformPermeability
  // Every pore voxel's permeability [m^2] when `permeability` is empty: a pore-resolved CT's medium, one value in
  // every pore (issue 23: an array of one repeated value was 8 bytes and a page-fault's share of time per voxel of
  // a whole-scan region).
  double uniformPermeability = 0.0;

  double permeabilityAt(std::size_t c) const { return permeability.empty() ? uniformPermeability : permeability[c]; }

  std::size_t count() const { return std::size_t(size[0]) * std::size_t(size[1]) * std::size_t(size[2]); }
  std::size_t index(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(size[0]) * (std::size_t(j) + std::size_t(size[1]) * std::size_t(k));
  }
  std::array<int, 3> ijk(std::size_t c) const {
    const int i = int(c % std::size_t(size[0]));
    const std::size_t r = c / std::size_t(size[0]);
    return {i, int(r % std::size_t(size[1])), int(r / std::size_t(size[1]))};
  }
  Eigen::Vector3d centre(std::size_t c) const {
    const auto v = ijk(c);
    return origin + spacing.cwiseProduct(Eigen::Vector3d(v[0], v[1], v[2]));
  }
  double voxelVolume() const { return spacing.prod(); }
  // A uniform medium (tests, the continuum oracles).
  static VoxelMedium uniform(std::array<int, 3> size, const Eigen::Vector3d& origin, const Eigen::Vector3d& spacing,
                             double porosity, double permeability);
};

// The pressure system in compressed rows (each row's columns in increasing order, the diagonal stored) and
// its solver: preconditioned conjugate gradient with MIC(0), the modified incomplete Cholesky factor with no
// fill (Gustafsson 1978; the voxel-grid form of Bridson, Fluid Simulation for Computer Graphics, 2nd ed.,
// sec. 5.3: tau 0.97, safety 0.25). On the voxels' 7-point systems it needs O(h^-1/2) iterations against
// Jacobi's O(h^-1); the factor is one pass over the matrix, so it is rebuilt every solve. Sequential (the
// triangular sweeps are): results do not depend on the thread count, and two threads on a loaded machine
// cannot be slower than one. Stopping test as Eigen's ConjugateGradient: |b - A x| <= tolerance |b|.
struct PressureSystem {
  std::vector<int> rowStart{0}, column, diagonal; // diagonal[row]: position of the row's diagonal entry
  std::vector<double> value;
  int rows() const { return int(rowStart.size()) - 1; }
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const; // y = A x
};

class PressureSolver {
public:
  struct Result {
    int iterations = 0;
    double relativeResidual = 0.0;
    bool converged = true;
  };
  // Solves A x = b from the guess in x (resized to zeros when its size differs).
  Result solve(const PressureSystem& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
               int maxIterations);
  // The same on arrays of A.rows() values (x: the guess, then the solution).
  Result solve(const PressureSystem& A, const double* b, double* x, double tolerance, int maxIterations);

  // The voxels' 7-point system written straight into the solver, row after row in order (the filling's
  // assembly: no compressed rows in between), the MIC(0) factor made as the rows come; then solveRows. A
  // row: its diagonal, its couplings to rows i - 1 and i + 1 (0: none), and at most two other lower and two
  // other upper couplings, columns in increasing order. The same arithmetic, in the same order, as
  // solve(PressureSystem) on the same matrix.
  void startRows(int n);
  void setRow(int i, double diagonal, double previous, double next, int lowerCount, const int* lowerColumn,
              const double* lowerValue, int upperCount, const int* upperColumn, const double* upperValue);
  Result solveRows(const double* b, double* x, double tolerance, int maxIterations);

private:
  void pad(const PressureSystem& A); // the padded copy and its MIC(0) factor
  template <int L, int U> double multiplyPadded(const double* x, double* y, int n) const; // y = A x; returns x . y
  // x += alpha p, r -= alpha q and the preconditioner's forward sweep of the new r into z; returns |r|^2
  template <int L, int U>
  double updateAndForward(double alpha, double* x, const double* p, double* r, const double* q, double* z, int n) const;
  template <int L, int U> double backward(const double* r, double* z, int n) const; // its backward sweep; returns r . z
  template <int L, int U> Result run(int n, const double* b, double* x, double tolerance, int maxIterations);
  int rows_ = 0, usedLower_ = 0, usedUpper_ = 0; // startRows' n; the most lower and upper slots a row used
  std::vector<double> pivot_, inversePivot_, previousScaled_, nextScaled_, upperSum_, r_, z_, p_, q_;
  int lowerWidth_ = 0, upperWidth_ = 0;
  bool rowsPacked_ = false; // solveRows repacked the rows to the used widths (a second solveRows must not again)
  std::vector<int> lowerColumn_, upperColumn_;
  std::vector<double> lowerValue_, upperValue_, diagonalValue_, previous_, next_; // a_i,i-1 and a_i,i+1 (or 0)
};

// The filling's per-voxel state in bricks of 8 x 8 x 8 voxels, allocated when first written (the cement or
// its front reaching them) and initialised to the values a voxel the cement never reached has. A 7.5 M voxel
// region with 50 k voxels of cement holds a few hundred bricks (29 kB each) and a directory of 4 bytes per
// brick, instead of 51 bytes per region voxel.
class VoxelBricks {
public:
  static constexpr int kEdgeBits = 3, kEdge = 1 << kEdgeBits, kVoxels = kEdge * kEdge * kEdge;
  // One voxel's values together (48 bytes): a pass reads several of a voxel and its neighbours at once,
  // and field arrays 4 kB apart in a brick would meet in the same cache sets. The flags and the row
  // numbers, which the front search and the assembly read for every neighbour, are kept apart, a byte
  // and 4 bytes a voxel (their working set is then that of dense arrays, not 48 bytes a voxel).
  struct Voxel {
    double fill = 0, pressure = 0, viscosity = 1, arrival = -1;
    float faceFlux[3] = {0, 0, 0}; // (+x, +y, +z) faces of the last solve [m^3/s]
  };
  // kClosedFlag: an impermeable voxel (porosity 0), set when the brick is allocated (touch with the
  // porosity) and cleared by openVoxels: the assembly reads it with the neighbour's other flags instead of
  // the region-sized porosity array.
  enum : std::uint8_t { kFilledFlag = 1, kBarredFlag = 2, kInFrontFlag = 4, kClosedFlag = 8 };
  struct Brick {
    std::uint8_t flags[kVoxels] = {}; // kFilledFlag | kBarredFlag | kInFrontFlag | kClosedFlag
    std::int32_t unknown[kVoxels];    // row of the pressure system (filled voxels), or -1
    Voxel voxel[kVoxels];             // local index (k % 8) * 64 + (j % 8) * 8 + i % 8
    Brick() { std::fill(unknown, unknown + kVoxels, -1); }
  };
  struct Cell {
    Brick* brick = nullptr; // null: a brick not allocated (every value at its initial one)
    int local = 0;
    Voxel* operator->() const { return &brick->voxel[local]; }
    std::int32_t& unknown() const { return brick->unknown[local]; }
    bool has(std::uint8_t flag) const { return brick->flags[local] & flag; } // (any of the flags in `flag`)
    void set(std::uint8_t flag, bool on) const {
      brick->flags[local] = std::uint8_t(on ? brick->flags[local] | flag : brick->flags[local] & ~flag);
    }
  };
  void reset(const std::array<int, 3>& size);
  // The voxel (i, j, k) (inside the region): shifts and masks only, what the per-step passes use.
  Cell find(int i, int j, int k) const {
    const std::int32_t at = directory_[std::size_t(k >> kEdgeBits) * bricksXY_ + std::size_t(j >> kEdgeBits) * bricksX_ +
                                       std::size_t(i >> kEdgeBits)];
    const int local = ((k & (kEdge - 1)) << (2 * kEdgeBits)) | ((j & (kEdge - 1)) << kEdgeBits) | (i & (kEdge - 1));
    return {at < 0 ? nullptr : bricks_[std::size_t(at)].get(), local};
  }
  Cell find(std::size_t c) const {
    const std::array<int, 3> v = ijk(c);
    return find(v[0], v[1], v[2]);
  }
  // VoxelMedium::ijk without its two divisions where the index fits 32 bits: a multiply by a precomputed
  // inverse (Lemire, Kaser & Kurz 2019, Softw. Pract. Exp. 49:953, exact for 32-bit dividends and divisors).
  std::array<int, 3> ijk(std::size_t c) const {
    if (c <= 0xffffffffu) {
      const std::uint32_t r = quotient(std::uint32_t(c), inverseX_, std::uint32_t(size_[0]));
      const std::uint32_t k = quotient(r, inverseY_, std::uint32_t(size_[1]));
      return {int(std::uint32_t(c) - r * std::uint32_t(size_[0])), int(r - k * std::uint32_t(size_[1])), int(k)};
    }
    const std::size_t nx = std::size_t(size_[0]), ny = std::size_t(size_[1]), r = c / nx;
    return {int(c % nx), int(r % ny), int(r / ny)};
  }
  // The neighbour of the voxel at `v` in `own` (allocated) one step along `axis` (0-2) by `sign` (+-1), inside
  // the region: in the same brick unless `v` is on the brick's side.
  Cell neighbour(const Cell& own, const std::array<int, 3>& v, int axis, int sign) const {
    const int shift = axis * kEdgeBits, along = (own.local >> shift) & (kEdge - 1);
    if (sign > 0 ? along != kEdge - 1 : along != 0) return {own.brick, own.local + sign * (1 << shift)};
    std::array<int, 3> w = v;
    w[std::size_t(axis)] += sign;
    return find(w[0], w[1], w[2]);
  }
  // The voxel's brick, allocated (viscosity from `initialViscosity` when not empty, else 1; kClosedFlag where
  // `porosity`, when given, is 0) if it was not.
  Cell touch(std::size_t c, const std::vector<double>& initialViscosity, const std::vector<float>* porosity = nullptr);
  std::size_t allocated() const { return bricks_.size(); }
  std::size_t bytes() const { return bricks_.size() * sizeof(Brick) + directory_.size() * sizeof(std::int32_t); }
  // f(voxel, brick, local) over the voxels of the allocated bricks that lie in the region
  template <class F> void forEachVoxel(F&& f) const {
    for (std::size_t b = 0; b < bricks_.size(); ++b)
      for (int local = 0; local < kVoxels; ++local) {
        const int i = origin_[b][0] + (local & (kEdge - 1)), j = origin_[b][1] + ((local >> kEdgeBits) & (kEdge - 1)),
                  k = origin_[b][2] + (local >> (2 * kEdgeBits));
        if (i >= size_[0] || j >= size_[1] || k >= size_[2]) continue;
        f(std::size_t(i) + std::size_t(size_[0]) * (std::size_t(j) + std::size_t(size_[1]) * std::size_t(k)), *bricks_[b], local);
      }
  }

private:
  __extension__ typedef unsigned __int128 Wide;
  static std::uint32_t quotient(std::uint32_t n, std::uint64_t inverse, std::uint32_t d) {
    return d == 1 ? n : std::uint32_t((Wide(inverse) * n) >> 64);
  }
  std::array<int, 3> size_{0, 0, 0};
  std::uint64_t inverseX_ = 0, inverseY_ = 0; // 2^64 / n + 1 for n = size x, size y (unused when n is 1)
  std::size_t bricksX_ = 0, bricksXY_ = 0;
  std::vector<std::int32_t> directory_; // per brick of the region: its index in bricks_, or -1
  std::vector<std::unique_ptr<Brick>> bricks_;
  std::vector<std::array<int, 3>> origin_; // first voxel of each allocated brick
};

// A read-only view of one per-voxel field of the filling, indexed by voxel like the dense vector it
// replaces (voxels the cement never came near read their initial value). operator std::vector makes the
// dense copy, region-sized, for a caller that wants one.
template <class T> class VoxelField {
public:
  using Member = T VoxelBricks::Voxel::*;
  VoxelField(const VoxelBricks* bricks, Member member, std::size_t count, T initial, const std::vector<T>* dense = nullptr)
      : bricks_(bricks), member_(member), count_(count), initial_(initial), dense_(dense) {}
  T operator[](std::size_t c) const {
    const VoxelBricks::Cell cell = bricks_->find(c);
    if (cell.brick) return cell.brick->voxel[cell.local].*member_;
    return dense_ && !dense_->empty() ? (*dense_)[c] : initial_;
  }
  std::size_t size() const { return count_; }
  operator std::vector<T>() const {
    std::vector<T> v(count_);
    for (std::size_t c = 0; c < count_; ++c) v[c] = (*this)[c];
    return v;
  }

private:
  const VoxelBricks* bricks_;
  Member member_;
  std::size_t count_;
  T initial_;
  const std::vector<T>* dense_;
};

struct FillingSettings {
  double maxFillPerStep = 1.0;   // largest overshoot of a voxel beyond full in one step, of its pore volume (excess moves on)
  // Conjugate gradient relative residual |b - A x| <= tolerance |b|. 1e-4 takes 18 iterations a solve on the
  // 5 ml phantom run against 30 at 1e-6 (40 at 1e-8). The filling's path is sensitive to any small change (a
  // voxel filling one step earlier), so every tolerance moves the 5 ml run's cement labels by about as much:
  // against 1e-8, 1e-4 changes 89 of its 45 120 labelled voxels and 1e-6 88, the tip pressure by 8e-5 and
  // 1e-4; the time step's own error is larger (the 1 % step cap against a 0.1 % cap: 158 voxels). The 1 ml
  // run: 15 of 9007 voxels at 1e-4, none at 1e-6. 1e-3 (12 iterations) moves the 5 ml run no more (95), but
  // one step's pressure then differs from the direct solve by 1.2e-4 of the largest (VoxelDarcySolver's
  // bound is 1e-4). Data/foam-phantom was remade at 1e-4 by its recorded command (PhantomRegression).
  double solverTolerance = 1e-4;
  int maxSolverIterations = 5000;
  double frontPressurePa = 0.0;     // pressure of the displaced fluid at the front [Pa gauge]
};

struct FillingStatistics {
  std::size_t steps = 0, solves = 0, iterations = 0, unconverged = 0;
  double worstResidual = 0.0, solveSeconds = 0.0, assemblySeconds = 0.0;
  std::size_t lastUnknowns = 0, lastFrontVoxels = 0;
  std::size_t capillaryRounds = 0; // solves of the capillary entry's open/barred iteration
  std::size_t bricks = 0, brickBytes = 0; // per-voxel state allocated (VoxelBricks), after the last step
};

// A run that cannot go on (the pore space connected to the source is full; a solve that diverges).
class FillingError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

class VoxelDarcyFilling {
public:
  // Throws std::invalid_argument for an empty or inconsistent medium.
  VoxelDarcyFilling(VoxelMedium medium, FillingSettings settings = {});

  // The cannula outlet: pore voxels whose centres lie within `radius` [m] of `centre` [m] (at least the voxel
  // containing the centre). Throws std::invalid_argument when the centre is outside or in an impermeable voxel.
  void setSource(const Eigen::Vector3d& centre, double radius);
  // Opens impermeable voxels to the cement from now on, each with its porosity (0, 1] and permeability
  // [m^2] (the tract a withdrawn cannula leaves). Voxels already open are left as they are. Throws
  // std::invalid_argument for a voxel outside the grid or a value out of range.
  void openVoxels(const std::vector<std::size_t>& voxels, const std::vector<float>& porosity,
                  const std::vector<double>& permeability);

  // Viscosity [Pa s] of every voxel for the next steps (a Newtonian cement: one value). A law that varies
  // per voxel (shear-thinning) sets them with setVoxelViscosity.
  void setViscosity(double viscosityPaS);
  // Capillary entry pressure of each voxel [Pa] (empty: none): a front voxel takes cement only while the
  // cement beside it is above p_front + its entry pressure (the cement as the non-wetting phase entering a
  // pore throat, Young-Laplace 2 sigma cos(theta) / r). With none, the front is at p_front everywhere.
  void setEntryPressure(std::vector<float> entryPressurePa);
  void setVoxelViscosity(std::vector<double> viscosityPaS);
  // A shear-thinning cement: each voxel's viscosity mu(gamma_dot) from its Darcy-scale shear rate
  // (rheology::darcyShearRate with the law's flow index), re-evaluated `picardIterations` times per step (solve,
  // shear rates from the new fluxes, viscosities, solve again); the first evaluation uses the last step's
  // fluxes. `law` must return a finite positive bounded viscosity (rheology::Rheology::viscosity does). An empty
  // law goes back to the viscosity set by setViscosity.
  void setShearRateViscosity(std::function<double(double)> law, double flowIndex, int picardIterations = 3);

  // Advances by at most dtMax [s] at the flow rate [m^3/s]; returns the step taken (> 0). Throws FillingError
  // when the cement has nowhere to go.
  // `stopAfter` [s] ends this call early without shortening the step (an output time, e.g. a snapshot's):
  // the step's length is chosen from dtMax and the fill limit as without it, the filling advances by
  // min(step, stopAfter), and the next call goes on with the rest of the step at the same inflows, without a
  // new pressure solve, as long as its flow rate is the same and nothing else changed the medium or the
  // outlet (openVoxels, setSource, setEntryPressure, setVoxelViscosity start a fresh step). Within a step
  // the inflows are constant (explicit in time), so a run stopped at output times takes the steps a run
  // without them takes: its pressure solves do not multiply with the outputs. setViscosity and
  // setShearRateViscosity (a curing or shear-thinning cement, set every call) do not restart the step: its rest
  // keeps the inflows solved at its start, as in a run without outputs.
  double step(double flowRate, double dtMax, double stopAfter = std::numeric_limits<double>::infinity());

  // The state.
  const VoxelMedium& medium() const { return medium_; }
  double time() const { return time_; }
  double injectedVolume() const { return injected_; }    // [m^3]
  double cementVolume() const;                           // sum of f phi V over the voxels [m^3]
  // Per-voxel fields, indexed by voxel (VoxelField: voxels the cement never came near read their initial value).
  VoxelField<double> fill() const { return {&bricks_, &VoxelBricks::Voxel::fill, medium_.count(), 0.0}; }
  // [Pa]; front voxels p_front, empty 0
  VoxelField<double> pressure() const { return {&bricks_, &VoxelBricks::Voxel::pressure, medium_.count(), 0.0}; }
  // Current on the voxels holding cement and the front (elsewhere the value they last had there, or 1).
  VoxelField<double> viscosity() const {
    return {&bricks_, &VoxelBricks::Voxel::viscosity, medium_.count(), 1.0, &voxelViscosity_};
  }
  // first cement in the voxel [s]; -1 none
  VoxelField<double> arrivalTime() const { return {&bricks_, &VoxelBricks::Voxel::arrival, medium_.count(), -1.0}; }
  bool filled(std::size_t c) const {
    const VoxelBricks::Cell cell = bricks_.find(c);
    return cell.brick && cell.has(VoxelBricks::kFilledFlag);
  }
  const std::vector<std::size_t>& sourceVoxels() const { return source_; }
  // Every voxel cement has reached, in order of arrival (a superset of those with fill > 0): what a caller
  // visits to walk the cement in time proportional to it, not to the region.
  const std::vector<std::size_t>& wetVoxels() const { return wet_; }
  // Superficial (Darcy) velocity at a voxel centre from its face fluxes of the last solve [m/s].
  Eigen::Vector3d darcyVelocity(std::size_t c) const;
  // A voxel's fields together, as fill(), pressure(), viscosity(), arrivalTime() and darcyVelocity() give them,
  // from one brick lookup instead of one each (a snapshot reads all of them for every voxel with cement).
  struct VoxelState {
    double fill = 0, pressure = 0, viscosity = 1, arrival = -1;
    Eigen::Vector3d darcyVelocity = Eigen::Vector3d::Zero();
  };
  VoxelState voxelState(std::size_t c) const;
  // Visits every voxel of wetVoxels(), in order of arrival, as visit(voxel, state) with its voxelState, read
  // from the brick place the filling keeps for it: no lookup per voxel (the snapshots during a run, issue 23).
  template <class Visit> void forEachWetVoxel(Visit&& visit) const {
    VoxelState s;
    for (std::size_t i = 0; i < wet_.size(); ++i) {
      const VoxelBricks::Cell& own = wetCell_[i];
      const VoxelBricks::Voxel& x = *own.operator->();
      s.fill = x.fill;
      s.pressure = x.pressure;
      s.viscosity = x.viscosity;
      s.arrival = x.arrival;
      s.darcyVelocity = darcyVelocityAt(own, bricks_.ijk(wet_[i]));
      visit(wet_[i], s);
    }
  }
  // Pore-volume weighted mean pressure of the source voxels (the pressure the cannula works against) [Pa].
  double sourcePressure() const;
  // The last step's inflow into each front voxel that took cement (voxel, m^3/s; a voxel once, in voxel
  // order; scaled so that the inflows add up to the flow rate): where the cement was going, e.g. the share of
  // it leaving the bone (the driver's leak-risk figure).
  const std::vector<std::pair<std::size_t, double>>& frontInflow() const { return inflow_; }
  // The capillary entry pressure of each voxel [Pa] (empty: none; setEntryPressure).
  const std::vector<float>& entryPressure() const { return entryPressure_; }
  const FillingStatistics& statistics() const { return stats_; }

private:
  enum : std::uint8_t { kClosed = 0, kEmpty = 1, kFilled = 2 };
  double poreVolume(std::size_t c) const { return double(medium_.porosity[c]) * voxelVolume_; }
  // closed: impermeable (porosity 0); filled: in its brick; else empty (a pore voxel without or with some cement)
  std::uint8_t state(std::size_t c, const VoxelBricks::Cell& cell) const {
    return medium_.porosity[c] <= 0 ? kClosed : cell.brick && cell.has(VoxelBricks::kFilledFlag) ? kFilled : kEmpty;
  }
  std::uint8_t state(std::size_t c) const { return state(c, bricks_.find(c)); }
  double viscosityAt(std::size_t c, const VoxelBricks::Cell& cell) const {
    return cell.brick ? cell->viscosity : voxelViscosity_.empty() ? 1.0 : voxelViscosity_[c];
  }
  double mobility(std::size_t c, const VoxelBricks::Cell& cell) const {
    return medium_.permeabilityAt(c) / viscosityAt(c, cell);
  }
  VoxelBricks::Cell touch(std::size_t c) { return bricks_.touch(c, voxelViscosity_, &medium_.porosity); }
  // A front voxel held back by its capillary entry pressure this step (front voxels' bricks are allocated).
  bool barredAt(std::size_t c) const {
    const VoxelBricks::Cell cell = bricks_.find(c);
    return cell.brick && cell.has(VoxelBricks::kBarredFlag);
  }
  void setBarred(std::size_t c, bool barred) {
    const VoxelBricks::Cell cell = touch(c);
    cell.set(VoxelBricks::kBarredFlag, barred);
  }
  // darcyVelocity of the voxel at `v` in `own` (allocated).
  Eigen::Vector3d darcyVelocityAt(const VoxelBricks::Cell& own, const std::array<int, 3>& v) const {
    Eigen::Vector3d q;
    for (int a = 0; a < 3; ++a) {
      double minus = 0;
      if (v[std::size_t(a)] > 0) {
        const VoxelBricks::Cell below = bricks_.neighbour(own, v, a, -1);
        if (below.brick) minus = below->faceFlux[a];
      }
      q[a] = 0.5 * (double(own->faceFlux[a]) + minus) / faceArea_[std::size_t(a)];
    }
    return q;
  }
  float faceFlux(std::size_t c, int axis) const {
    const VoxelBricks::Cell cell = bricks_.find(c);
    return cell.brick ? cell->faceFlux[axis] : 0.0f;
  }
  void depositExcess(std::size_t from, double volume);
  // Fills the front voxels by the last solve's inflows (inflow_) for dt at the flow rate; moves the time on.
  void advanceFill(double flowRate, double dt);
  void updateShearViscosity();
  void markFilled(std::size_t c);
  void wet(std::size_t c); // the first cement in a voxel: its arrival time, the list of voxels with cement
  void findFront();        // front_: the pore voxels beside the cement, in voxel order

  VoxelMedium medium_;
  FillingSettings settings_;
  double voxelVolume_ = 0.0;
  std::array<double, 3> faceArea_{}, faceDistance_{};
  VoxelBricks bricks_;                  // fill, pressure, viscosity, arrival, face fluxes, numbering, flags
  std::vector<double> voxelViscosity_;  // setVoxelViscosity's values (empty: not used)
  std::vector<std::size_t> source_;
  double time_ = 0.0, injected_ = 0.0;
  // The rest of a step that a call's stopAfter cut short [s] (0: none) and its flow rate [m^3/s].
  double pendingDt_ = 0.0, pendingFlowRate_ = 0.0;
  FillingStatistics stats_;
  std::vector<float> entryPressure_;  // per voxel [Pa]; empty: no capillary entry
  std::vector<std::pair<std::size_t, double>> inflow_; // the last step's inflow per front voxel [m^3/s]
  std::function<double(double)> shearLaw_;
  double flowIndex_ = 1.0;
  int picardIterations_ = 1;
  // The active set (issue 23): the filled voxels in voxel order (filled_; newlyFilled_ since the last
  // merge), the front, the voxels with cement, and those whose face fluxes were written.
  std::vector<std::size_t> filled_, newlyFilled_, front_, wet_;
  std::vector<VoxelBricks::Cell> filledCell_, wetCell_; // each filled_ (wet_) voxel's brick and place in it
  // Each wet_ voxel's pore volume [m^3], beside it: cementVolume() runs at every snapshot, and the porosity
  // array's scattered reads were most of its time (issue 23's snapshot target).
  std::vector<double> wetPoreVolume_;
  std::vector<VoxelBricks::Cell> frontCell_;            // the front's, alongside front_
  std::vector<std::size_t> justFilled_;                // voxels filled since the last findFront
  std::vector<std::pair<std::size_t, VoxelBricks::Cell>> frontAdded_; // findFront's newcomers (buffer)
  bool frontStale_ = true;                             // findFront searches from every filled voxel
  std::vector<std::array<int, 3>> filledIjk_;          // and each filled_ voxel's (i, j, k)
  std::vector<std::size_t> mergedVoxels_;              // step's merge of newlyFilled_ into filled_ (buffers)
  std::vector<VoxelBricks::Cell> mergedCells_;
  std::vector<std::array<int, 3>> mergedIjk_;
  bool uniformViscosity_ = true; // every voxel's viscosity is viscosityValue_ (setViscosity)
  double viscosityValue_ = 1.0;
  PressureSolver solver_;
  std::vector<double> rhs_, solution_; // the system's right-hand side and the solve's guess, then solution
  // The assembly's per-row mobility and, per row and axis, the transmissibility of the face to the filled
  // voxel above (+x, +y, +z; written only where that voxel is filled), kept for the face fluxes.
  std::vector<double> rowMobility_, upperTransmissibility_;
};

} // namespace cementsph::voxeldarcy
