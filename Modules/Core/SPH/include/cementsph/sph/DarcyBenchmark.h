// The paper's Darcy validation ("Darcy Flow Simulation", Figs. 1, 4, 5): a periodic cubic lattice of
// particles, a random (seeded) subset fixed to a given porosity, a constant body force along x, run to
// a detected steady state; the mean velocity through the mid-plane against the body force gives, by
// Eq. 12, the permeability k = mu eps u_bar / (rho0 F_B).
//
// Dimensionless permeability is k / d^2 with d the particle spacing (model-notes 2: Jiang et al. do not
// state their normalising length; the spacing is the natural one, and the Kozeny-Carman curve we
// compare with uses the same d as grain diameter).
#pragma once

#include "cementsph/sph/ModelParameters.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace cementsph::sph {

struct SteadyStateCriteria {
  // Fluid particles rearrange as they flow past fixed ones, so the mid-plane velocity is a function
  // of the distance travelled, periodic with the lattice spacing d (measured: +-2 % about its mean
  // once about one spacing has been travelled). The steady state is therefore judged in travel, not
  // time: the mean velocity over a window of `windowTravel` spacings (a whole period) is compared with
  // the previous window's, and the run is steady when they agree to `relativeTolerance`.
  double windowTravel = 1.0;       // [spacings]
  double relativeTolerance = 1e-2;
  int agreeingWindows = 1;         // consecutive agreeing window pairs needed
  std::uint64_t maxSteps = 400000; // per body force
};

struct DarcyCase {
  int latticeSize = 25;              // particles per side (the paper: 25^3)
  double spacing = 1e-3;             // d [m]
  double porosity = 0.7;             // 1 - fixed / all
  double viscosity = 10.0;           // mu [Pa s]
  std::uint64_t seed = 1;            // random choice of fixed sites
  std::vector<double> bodyForces;    // F_B [m/s^2]; empty: the default sweep (bodyForceSweep)
};

struct DarcyPoint {
  double bodyForce = 0;     // [m/s^2]
  double meanVelocity = 0;  // u_bar: mean x-velocity of fluid particles in the mid-plane slab [m/s]
  std::uint64_t steps = 0;  // for this force
  double simulatedTime = 0; // [s], for this force
  bool converged = false;
};

struct DarcyResult {
  DarcyCase input;
  double porosity = 0;          // realised: 1 - fixed / all
  double slope = 0;             // u_bar / F_B from the least-squares line through the origin [s]
  double intercept = 0;         // of the free least-squares line [m/s] (should be ~0)
  double r2 = 0;                // coefficient of determination of the free line
  double permeability = 0;      // k [m^2], Eq. 12
  double dimensionlessPermeability = 0; // k / d^2
  std::uint64_t steps = 0;      // all body forces together
  double wallSeconds = 0;
  bool converged = false;       // every body force reached a steady state
  std::vector<DarcyPoint> points;
};

// Kozeny-Carman k / dp^2 = phi^3 / (180 (1 - phi)^2) (model-notes 4).
double kozenyCarmanDimensionless(double porosity);

// Body forces for a sweep: F = f * 2e-3 cs^2 / d, f = 1, 0.8, 0.6, 0.4 (largest first: the run
// continues from one force's steady state to the next). Smaller forces are closer to the quasi-static
// limit but need proportionally more steps per spacing travelled; at this scale u / F differs from
// that at 4x the force by ~10 % (measured, porosity 0.7), hence the fit's R^2 is reported.
std::vector<double> bodyForceSweep(const ModelParameters& model, double spacing);

// Model parameters of one Darcy case: h = hOverD * d, the given viscosity.
ModelParameters darcyModel(const ModelParameters& base, double hOverD, double spacing, double viscosity);

class DarcyBenchmark {
public:
  using Progress = std::function<void(const std::string&)>;
  DarcyBenchmark(ModelParameters base, double hOverD, SteadyStateCriteria criteria = {})
      : base_(std::move(base)), hOverD_(hOverD), criteria_(criteria) {}

  // The sweep of body forces on one random medium, each to its steady state, and the fit of Eq. 12.
  DarcyResult run(const DarcyCase& c, const Progress& progress = {}) const;

private:
  ModelParameters base_;
  double hOverD_;
  SteadyStateCriteria criteria_;
};

} // namespace cementsph::sph
