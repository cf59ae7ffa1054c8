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
//    (lists kept as the cement grows). What remains in proportion to the region: the constructor's check
//    of the medium and the per-voxel arrays the accessors below return (their memory, not per-step time).
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
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
  std::vector<double> permeability; // per voxel [m^2] (ignored where porosity is 0)

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

private:
  void pad(const PressureSystem& A);
  void factor(const PressureSystem& A);
  template <int L, int U> void multiplyPadded(const double* x, double* y, int n) const;
  template <int L, int U> void preconditionPadded(const double* r, double* z, int n) const;
  template <int L, int U>
  Result run(const PressureSystem& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int maxIterations);
  Eigen::VectorXd pivot_, inversePivot_, previousScaled_, nextScaled_, upperSum_, r_, z_, p_, q_;
  int lowerWidth_ = 0, upperWidth_ = 0;
  std::vector<int> lowerColumn_, upperColumn_;
  std::vector<double> lowerValue_, upperValue_, diagonalValue_, previous_, next_; // a_i,i-1 and a_i,i+1 (or 0)
};

struct FillingSettings {
  double maxFillPerStep = 1.0;   // largest overshoot of a voxel beyond full in one step, of its pore volume (excess moves on)
  double solverTolerance = 1e-6;  // conjugate gradient relative residual (1e-8 moved the 5 ml phantom run by < 0.01 %)
  int maxSolverIterations = 5000;
  double frontPressurePa = 0.0;     // pressure of the displaced fluid at the front [Pa gauge]
};

struct FillingStatistics {
  std::size_t steps = 0, solves = 0, iterations = 0, unconverged = 0;
  double worstResidual = 0.0, solveSeconds = 0.0, assemblySeconds = 0.0;
  std::size_t lastUnknowns = 0, lastFrontVoxels = 0;
  std::size_t capillaryRounds = 0; // solves of the capillary entry's open/barred iteration
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
  double step(double flowRate, double dtMax);

  // The state.
  const VoxelMedium& medium() const { return medium_; }
  double time() const { return time_; }
  double injectedVolume() const { return injected_; }    // [m^3]
  double cementVolume() const;                           // sum of f phi V over the voxels [m^3]
  const std::vector<double>& fill() const { return fill_; }
  const std::vector<double>& pressure() const { return pressure_; } // [Pa]; front voxels p_front, empty 0
  // Current on the voxels holding cement and the front (elsewhere the value they last had there, or 1).
  const std::vector<double>& viscosity() const { return viscosity_; }
  const std::vector<double>& arrivalTime() const { return arrival_; } // first cement in the voxel [s]; -1 none
  bool filled(std::size_t c) const { return state_[c] == kFilled; }
  const std::vector<std::size_t>& sourceVoxels() const { return source_; }
  // Every voxel cement has reached, in order of arrival (a superset of those with fill > 0): what a caller
  // visits to walk the cement in time proportional to it, not to the region.
  const std::vector<std::size_t>& wetVoxels() const { return wet_; }
  // Superficial (Darcy) velocity at a voxel centre from its face fluxes of the last solve [m/s].
  Eigen::Vector3d darcyVelocity(std::size_t c) const;
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
  double mobility(std::size_t c) const { return medium_.permeability[c] / viscosity_[c]; }
  void depositExcess(std::size_t from, double volume);
  void updateShearViscosity();
  void markFilled(std::size_t c);
  void wet(std::size_t c); // the first cement in a voxel: its arrival time, the list of voxels with cement
  void findFront();        // front_: the pore voxels beside the cement, in voxel order

  VoxelMedium medium_;
  FillingSettings settings_;
  double voxelVolume_ = 0.0;
  std::array<double, 3> faceArea_{}, faceDistance_{};
  std::vector<std::uint8_t> state_;
  std::vector<double> fill_, pressure_, viscosity_, arrival_;
  std::vector<float> faceFlux_; // per voxel, 3 faces (+x, +y, +z) of the last solve [m^3/s]
  std::vector<std::size_t> source_;
  double time_ = 0.0, injected_ = 0.0;
  FillingStatistics stats_;
  std::vector<int> unknown_; // voxel -> unknown index or -1
  std::vector<float> entryPressure_;  // per voxel [Pa]; empty: no capillary entry
  std::vector<std::uint8_t> barred_;  // front voxel held back by its entry pressure this step
  std::vector<std::pair<std::size_t, double>> inflow_; // the last step's inflow per front voxel [m^3/s]
  std::function<double(double)> shearLaw_;
  double flowIndex_ = 1.0;
  int picardIterations_ = 1;
  // The active set (issue 23): the filled voxels in voxel order (filled_; newlyFilled_ since the last
  // merge), the front, the voxels with cement, and those whose face fluxes were written.
  std::vector<std::size_t> filled_, newlyFilled_, front_, wet_, fluxWritten_;
  std::vector<std::uint8_t> inFront_;
  bool uniformViscosity_ = true; // every voxel's viscosity is viscosityValue_ (setViscosity)
  double viscosityValue_ = 1.0;
  PressureSystem system_;
  PressureSolver solver_;
};

} // namespace cementsph::voxeldarcy
