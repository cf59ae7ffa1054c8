// Cement viscosity as a function of time since the start of injection.
//
// Basafa et al. 2013 ("Foam Block Tests"): the cement was injected once its viscosity had reached 50, 100,
// 200 or 400 Pa.s (estimated from Hagen-Poiseuille, Eq. 13) and the viscosity "rises linearly in time" while
// it cures (model-notes 1, 5: real PMMA rises non-linearly; the linear schedule is the paper's simplification,
// a table lets a measured curve in). One value for the whole batch at each moment: the particle engine sets
// it each step (Simulation::setViscosity, read by the Eq. 9 drag), the voxel engine per pressure solve.
#pragma once

#include <utility>
#include <vector>

namespace cementsph::rheology {

class ViscositySchedule {
public:
  enum class Kind { Constant, Linear, Table };

  // mu(t) = mu0. Throws std::invalid_argument unless mu0 > 0 and finite.
  static ViscositySchedule constant(double viscosityPaS);
  // mu(t) = mu0 + rate t for t >= 0 (times before 0 read mu0). rate [Pa.s/s] must be >= 0 (curing cement
  // only thickens), so mu(t) stays positive. Throws std::invalid_argument otherwise.
  static ViscositySchedule linear(double initialViscosityPaS, double ratePaSPerS);
  // Piecewise linear through (time [s], viscosity [Pa.s]) points, held constant before the first and after
  // the last. Times strictly increasing, viscosities > 0, at least one point; std::invalid_argument otherwise.
  static ViscositySchedule table(std::vector<std::pair<double, double>> points);

  Kind kind() const { return kind_; }
  // Viscosity at time t [s] since the start of injection [Pa.s].
  double at(double timeS) const;
  double operator()(double timeS) const { return at(timeS); }

private:
  ViscositySchedule() = default;
  Kind kind_ = Kind::Constant;
  double mu0_ = 0.0, rate_ = 0.0;
  std::vector<std::pair<double, double>> points_;
};

} // namespace cementsph::rheology
