// Model and numerical parameters of the particle model, in SI units throughout.
// Equation numbers refer to Basafa et al. 2013 (PLoS ONE 8(6) e67958).
#pragma once

#include <Eigen/Core>

#include <functional>
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

// A continuum porous medium (bone whose pores the CT does not resolve): porosity phi and permeability k
// [m^2] at a point [m]. Used by the `permeability` resistance.
struct Medium {
  double porosity = 1.0;
  double permeability = 0.0;
};
using MediumField = std::function<Medium(const Eigen::Vector3d& positionM)>;

// Settings of the incompressible Darcy pressure model (Pressure/IncompressibleDarcy.h).
struct IncompressibleSettings {
  // A particle whose kernel sum of cement bulk and solid volume (theta) is below this is at the cement
  // front: marrow pressure (0 gauge) there. A flat free surface of a lattice has theta = 0.85 on its outer
  // layer and 1.00 one layer in (h = d), so 0.92 separates them with room for disorder.
  double frontVolumeFraction = 0.92;
  // ... or whose neighbours are one-sided: |grad theta| h above this (0.51 on a lattice's free surface).
  double frontGradient = 0.25;
  // Fraction of a particle's excess volume fraction (theta - 1 > 0) removed per relaxation time: the drift
  // correction that keeps the cement at its own volume.
  double volumeCorrection = 0.1;
  // The relaxation time [s]; 0: the run's maximum time step (an injection's emission interval d^3 / Q), or
  // the last step if unbounded.
  double relaxationTime = 0.0;
  double solverTolerance = 1e-6;    // relative residual of the conjugate-gradient solve
  int solverMaxIterations = 2000;
  // Relative diagonal shift towards the last pressure: keeps the system regular where cement has no front
  // (a closed cavity: the pressure then climbs step by step, as into a stiff, nearly incompressible fill).
  double regularisation = 1e-9;
};

struct ModelParameters {
  double restDensity = 1180.0;    // rho0 [kg/m^3], cement (paper)
  double soundSpeed = 1.0;        // cs [m/s], Eq. 6 (paper: 1 m/s)
  double smoothingLength = 1e-3;  // h [m]; kernels have support 2h (Eq. 10, 11)
  double viscosity = 100.0;       // mu [Pa s]
  double dragCoefficient = 1.0;   // Cf, Eq. 9 (dimensionless; calibrated, see VALIDATION.md)
  ViscosityModel viscosityModel = ViscosityModel::Drag;
  Integrator integrator = Integrator::Overdamped;
  // The interchangeable parts of a step by registered name (ModelRegistry.cpp). Empty: follow
  // viscosityModel (drag -> paper-drag, else none) and integrator.
  std::string pressureModel = "equation-of-state"; // or "incompressible"
  std::string resistance;                          // "paper-drag", "permeability" or "none"
  std::string viscosityLaw = "newtonian";
  std::string boundary = "domain-sides";
  IncompressibleSettings incompressible;
  // The continuum medium for the `permeability` resistance (unset: uniform `medium`).
  Medium medium;
  MediumField mediumField;
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
  double dragRate(double mass, double density) const { return dragRate(mass, density, viscosity); }
  double dragRate(double mass, double density, double mu) const {
    const double h = smoothingLength;
    return dragCoefficient * mass * mu / (density * density * h * h * h * h * h);
  }
  // The resistance's registered name (resistance, or the one viscosityModel implies).
  std::string resistanceName() const {
    if (!resistance.empty()) return resistance;
    return viscosityModel == ViscosityModel::Drag ? "paper-drag" : "none";
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
