// Model and numerical parameters of the particle model, in SI units throughout.
// Equation numbers refer to Basafa et al. 2013 (PLoS ONE 8(6) e67958).
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>

namespace cementsph::sph {

// Velocity-dependent force.
enum class ViscosityModel {
  None,   // inviscid (tests)
  Drag,   // the paper's Eq. 9: a = -Cf m mu / (rho^2 h^5) v, a particle's own velocity only
  Morris, // the standard SPH viscous term, Eq. 7 (Morris, Fox & Zhu 1997), pairwise
};

// Time integration scheme.
enum class Integrator {
  CentralDifference, // the paper's Eq. 8, with the Eq. 9 drag taken implicitly (diagonal)
  Explicit,          // symplectic Euler: for Morris viscosity, bound by viscous and acoustic limits
  Overdamped,        // creeping-flow limit of the drag model: v = a_other / gamma (model-notes 3)
};

// How the fixed particles' share of Eq. 2 and Eq. 5 is summed (FixedParticleField.h).
enum class FixedSumMethod {
  Exact,     // pair by pair, as the paper (every fixed particle within the support, every step)
  Tabulated, // summed once on a grid and interpolated (ours: open boxes, drag model only)
};

// What to do when a user-fixed time step exceeds the scheme's stability limit.
enum class StepLimitPolicy { Refuse, Clamp };

struct ModelParameters {
  double restDensity = 1180.0;    // rho0 [kg/m^3], cement (paper)
  double soundSpeed = 1.0;        // cs [m/s], Eq. 6 (paper: 1 m/s)
  double smoothingLength = 1e-3;  // h [m]; kernels have support 2h (Eq. 10, 11)
  double viscosity = 100.0;       // mu [Pa s]
  double dragCoefficient = 1.0;   // Cf, Eq. 9 (dimensionless; calibrated, see VALIDATION.md)
  ViscosityModel viscosityModel = ViscosityModel::Drag;
  Integrator integrator = Integrator::Overdamped;
  Eigen::Vector3d bodyForce = Eigen::Vector3d::Zero(); // F_B [m/s^2], force per unit mass

  // --- time stepping --------------------------------------------------------------------------
  std::optional<double> fixedTimeStep;       // [s]; when unset the step follows the limits below
  StepLimitPolicy stepLimitPolicy = StepLimitPolicy::Refuse;
  // Upper bound on the adaptive step [s] (unset: none). Added for the injection source, which emits at
  // most one particle per step (CannulaEmitter::maxTimeStep()). Ignored when fixedTimeStep is set.
  std::optional<double> maxTimeStep;
  double acousticCourant = 0.25;   // dt <= C h / cs (explicit pressure term)
  double viscousNumber = 0.125;    // dt <= C h^2 / nu (Morris et al. 1997), Explicit + Morris
  double forceCourant = 0.25;      // dt <= C sqrt(h / |a|max)
  double overdampedStability = 1.5; // Overdamped: dt <= C gamma h^2 / cs^2 (measured: stable at 2, not at 3)
  double maxDisplacement = 0.05;   // Overdamped: a particle moves at most this fraction of h per step

  // --- neighbour search -----------------------------------------------------------------------
  double neighbourSkin = 0.2;      // Verlet skin as a fraction of h; 0 rebuilds lists every step
  // Relisting (Simulation.h): a particle added while the lists are valid, or one that has moved half
  // the skin while few others have, gets lists of its own instead of a rebuild of all lists (the
  // injection adds a particle every few steps, and only those near the tip move fast). false: rebuild.
  bool relisting = true;

  // --- fixed particles ------------------------------------------------------------------------
  FixedSumMethod fixedSums = FixedSumMethod::Exact;
  double fixedFieldSpacing = 0.25; // Tabulated: node spacing as a fraction of h (VALIDATION.md: h/4)

  // --- safety ---------------------------------------------------------------------------------
  double runawaySpeedFactor = 10.0; // a particle faster than this many cs means the run went unstable

  // The drag rate gamma = Cf m mu / (rho^2 h^5) [1/s] of Eq. 9.
  double dragRate(double mass, double density) const {
    const double h = smoothingLength;
    return dragCoefficient * mass * viscosity / (density * density * h * h * h * h * h);
  }
  double pressure(double density) const { return soundSpeed * soundSpeed * (density - restDensity); }
};

std::string toString(ViscosityModel model);
std::string toString(Integrator integrator);
std::string toString(FixedSumMethod method);
ViscosityModel parseViscosityModel(const std::string& name);
Integrator parseIntegrator(const std::string& name);
FixedSumMethod parseFixedSumMethod(const std::string& name);

} // namespace cementsph::sph
