// Incompressible creeping (Darcy) flow of the cement (ours; replaces Eq. 6 where the scene is a viscous
// cement in a porous solid: docs/architecture.md, "Choosing a model").
//
// Assumptions: inertia negligible (Re << 1, Stokes number << 1), the cement incompressible (its bulk
// modulus, of order 1 GPa for PMMA dough, far above any injection pressure), Darcy's law at particle scale: the particle velocity
// is v = -lambda grad p with the mobility lambda = 1 / (rho0 gamma) from the resistance (Eq. 9: k0 / mu,
// k0 = h^5 / (Cf d^3); a permeability field: k / (phi mu)). The marrow ahead of the cement is at 0 gauge
// pressure and offers no resistance (cement/marrow viscosity ratio ~1e3-1e4); capillarity is neglected.
//
// Each step:
//  1. Volume fractions: theta_i = sum_j Omega_j W_ij + sum_s V_s W_is (cubic spline, Eq. 10), Omega_j =
//     m_j / (rho0 phi_j) the bulk volume a cement particle fills, V_s the solid volume of a fixed particle.
//     theta = 1 where cement and solid fill the kernel; below frontVolumeFraction a particle is at the front.
//  2. Pressure: the SPH Laplacian of Brookshaw (1985) with the harmonic mean of the mobilities,
//       (L p)_i = sum_j Omega_j lambda_ij G_ij (p_i - p_j),  G_ij = -2 r W'(r) / (r^2 + 0.01 h^2) >= 0,
//     is set equal to the divergence the particle's volume needs: the source (the cannula's flow rate Q over
//     the particles at the outlet, Q / phi of bulk per second) plus the drift correction
//     volumeCorrection (theta_i - 1) / tau (inside; at the front only an excess). Solid neighbours are absent from the sum: no flux into solid.
//     Front particles couple to the marrow (p = 0) through the part of a full kernel's sum they miss,
//     Omega_i lambda_i (Gamma - sum_present Omega_j G_ij), Gamma the sum of a full lattice: the Dirichlet
//     condition sits where their missing neighbours would be. Multiplied by Omega_i the system is symmetric
//     positive definite; Eigen's conjugate gradient with a Jacobi preconditioner solves it, warm-started
//     from the last step's pressures.
//  3. Velocity: v_i = -lambda_i B_i sum_j Omega_j (p_j - p_i) grad W_ij, B_i the inverse of the kernel's
//     moment matrix (exact for a linear pressure, also at the front), written as the acceleration the
//     drag balances (a = gamma v) for the overdamped integrator.
// Pressures are then gauge pressures in Pa, and the cement keeps its volume (tested).
#pragma once

#include "cementsph/sph/ModelInterfaces.h"
#include "cementsph/sph/ModelParameters.h"

#include <cstdint>
#include <vector>

namespace cementsph::sph {

struct PressureSolveStatistics {
  std::uint64_t solves = 0;
  std::uint64_t iterations = 0;       // over all solves
  int lastIterations = 0;
  double lastResidual = 0.0;          // relative
  double worstResidual = 0.0;
  std::uint64_t unconverged = 0;      // solves that stopped at the iteration cap
  double solveSeconds = 0.0;          // assembly + CG, all solves
  std::size_t lastUnknowns = 0;
  std::size_t lastFrontParticles = 0;
};

class IncompressibleDarcy : public PressureModel {
public:
  explicit IncompressibleDarcy(const ModelParameters& p) : settings_(p.incompressible) {}
  std::string name() const override { return "incompressible"; }
  void density(Simulation& sim) override;
  void pressure(Simulation& sim) override;
  bool makesAccelerations() const override { return true; }
  bool acoustic() const override { return false; }
  void stepDone(double dt) override { lastStep_ = dt; }

  const PressureSolveStatistics& statistics() const { return stats_; }
  // The sum over a full simple-cubic lattice of bulk spacing a of a^3 G(r) (the Gamma above), for h.
  static double fullKernelLaplacianSum(double h, double latticeSpacing);
  // Brookshaw's Laplacian of x^2, halved, on that lattice (1 if exact).
  static double laplacianLatticeFactor(double h, double latticeSpacing);

private:
  IncompressibleSettings settings_;
  double lastStep_ = 0.0;
  std::vector<double> solid_;         // sum_s V_s W_is per fluid particle
  std::vector<double> presentSum_;    // sum_j Omega_j G_ij over present (fluid and solid) neighbours
  std::vector<double> bulk_;          // Omega_i
  double gamma_ = 0.0, gammaH_ = 0.0, gammaSpacing_ = 0.0, latticeFactor_ = 1.0;
  PressureSolveStatistics stats_;
};

} // namespace cementsph::sph
