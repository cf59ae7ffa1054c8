// The interchangeable parts of one step (docs/architecture.md). Each is an interface with one folder per
// method (Pressure/, Resistance/, Viscosity/, Integrators/, Boundaries/), created by name from
// ModelRegistry; a new method is one new file and one registration line in ModelRegistry.cpp.
//
// One step of Simulation::step():
//   lists -> ViscosityLaw (mu_i) -> PressureModel (rho_i, p_i; Eq. 2 + Eq. 6, or the incompressible solve)
//   -> Resistance (gamma_i, Eq. 9 or k/mu) -> accelerations (Eq. 5 (+ Eq. 7), unless the pressure model
//   made them) -> TimeIntegrator (Eq. 8, explicit or overdamped) -> health check -> DomainBoundary.
#pragma once

#include <cstddef>
#include <limits>
#include <string>

namespace cementsph::sph {

class Simulation;

// Loops that do a few operations per particle run on one thread below this many particles: their work is
// microseconds, and every parallel loop ends in a barrier that costs far more when another program holds a
// core (measured: 2 threads 6x slower than 1 on a loaded 2-core machine). Shared by the engine and its models.
inline constexpr std::size_t kParallelMinimum = 16384;

// The time-step limits that apply to the current scheme [s]; +inf where a limit does not apply.
struct StepLimits {
  double acoustic = std::numeric_limits<double>::infinity();     // C h / cs: explicit pressure term
  double viscous = std::numeric_limits<double>::infinity();      // C h^2 / nu: explicit Morris viscosity
  double drag = std::numeric_limits<double>::infinity();         // 1 / gamma_max: explicit drag
  double force = std::numeric_limits<double>::infinity();        // C sqrt(h / |a|max)
  double overdamped = std::numeric_limits<double>::infinity();   // C gamma_min h^2 / cs^2: overdamped stability
  double displacement = std::numeric_limits<double>::infinity(); // maxDisplacement h / |v|max: overdamped accuracy
  double stable() const; // the smallest of the stability limits (all but displacement)
};

// Density and pressure of the fluid particles (and, for a model that solves for the velocity field
// itself, their accelerations).
class PressureModel {
public:
  virtual ~PressureModel() = default;
  virtual std::string name() const = 0;
  // Fills fluid().density for the current positions (lists are up to date); the resistance is then
  // computed from it.
  virtual void density(Simulation& sim) = 0;
  // Fills fluid().pressure (the resistance, fluid().dragRate, is known by now).
  virtual void pressure(Simulation& sim) = 0;
  // True when pressure() also fills fluid().ax/ay/az (the drag-balanced acceleration gamma v); the engine
  // then skips its Eq. 5 force pass.
  virtual bool makesAccelerations() const { return false; }
  // True when the pressure is a sound-speed equation of state, so the acoustic and overdamped-stability
  // step limits (cs) apply.
  virtual bool acoustic() const { return true; }
  // Called after each step with its length [s].
  virtual void stepDone(double /*dt*/) {}
};

// Resistance of the porous medium: fills fluid().dragRate (gamma [1/s], a = -gamma v).
class Resistance {
public:
  virtual ~Resistance() = default;
  virtual std::string name() const = 0;
  virtual void update(Simulation& sim) = 0;
};

// Viscosity of each particle: fills fluid().viscosity [Pa s].
class ViscosityLaw {
public:
  virtual ~ViscosityLaw() = default;
  virtual std::string name() const = 0;
  virtual void update(Simulation& sim) = 0;
};

class TimeIntegrator {
public:
  virtual ~TimeIntegrator() = default;
  virtual std::string name() const = 0;
  virtual StepLimits limits(const Simulation& sim) const = 0;
  virtual void integrate(Simulation& sim, double dt) = 0;
  // Eq. 8 keeps one step length once chosen.
  virtual bool constantStep() const { return false; }
};

// What happens at the sides of the simulation box (periodic re-entry or removal at open sides).
class DomainBoundary {
public:
  virtual ~DomainBoundary() = default;
  virtual std::string name() const = 0;
  // Returns how many particles left the domain (removed).
  virtual std::size_t apply(Simulation& sim) = 0;
};

} // namespace cementsph::sph
