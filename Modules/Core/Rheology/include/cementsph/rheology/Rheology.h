// Shear-rate dependent viscosity of the cement (issue "Cement rheology"): a law mu(gamma_dot) [Pa s] of
// the shear rate [1/s], one file per law in this folder (PowerLaw.h, Carreau.h), created by name in
// Rheology.cpp. The laws are plain functions: the voxel-grid Darcy model evaluates them per voxel at the
// Darcy-scale shear rate (darcyShearRate) and the cannula model integrates them over the bore (TubeFlow.h).
// Every law is bounded below and above (a power law has no finite limit at zero or infinite shear).
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace cementsph::rheology {

struct RheologyParameters {
  double viscosityPaS = 100.0;        // newtonian
  double consistencyPaSn = 100.0;     // power law K [Pa s^n]
  double flowIndex = 1.0;             // n (power law, Carreau)
  double zeroShearViscosityPaS = 100.0;     // Carreau mu0
  double infiniteShearViscosityPaS = 0.0;   // Carreau mu_inf
  double timeConstantS = 1.0;               // Carreau lambda
  double minimumViscosityPaS = 1e-3;  // bounds of the apparent viscosity
  double maximumViscosityPaS = 1e6;
};

class Rheology {
public:
  virtual ~Rheology() = default;
  virtual std::string name() const = 0;
  // The unbounded law at shear rate gammaDot >= 0 [1/s].
  virtual double unbounded(double gammaDot) const = 0;
  // The flow index the Darcy-scale shear rate uses (1 for Newtonian).
  virtual double flowIndex() const = 0;
  // The apparent viscosity, within the bounds [Pa s].
  double viscosity(double gammaDot) const;
  double minimum = 1e-3, maximum = 1e6;
};

// The registered laws' names, in registration order: "newtonian", "power-law", "carreau".
std::vector<std::string> rheologyNames();

// A law by its registered name; throws std::invalid_argument for another name or parameters
// out of range (one line naming the parameter).
std::unique_ptr<Rheology> makeRheology(const std::string& name, const RheologyParameters& parameters);

// Darcy-scale shear rate of a flow of superficial speed |q| [m/s] through a medium of permeability k [m^2]
// and porosity phi: gamma_dot = (3n + 1) / (4n) * 12 |q| / sqrt(150 k phi), Christopher & Middleman 1965
// (Ind. Eng. Chem. Fundam. 4:422; the capillary-bundle pore-scale factor, as reviewed by Sochi 2010,
// Polymer 51:5007). For n = 1 the factor is 12 / sqrt(150) = 0.98.
double darcyShearRate(double darcySpeedMPerS, double permeabilityM2, double porosity, double flowIndex);

} // namespace cementsph::rheology
