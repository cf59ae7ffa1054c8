#include "cementsph/sph/ModelParameters.h"

#include <stdexcept>

namespace cementsph::sph {

std::string toString(ViscosityModel model) {
  switch (model) {
  case ViscosityModel::None: return "none";
  case ViscosityModel::Drag: return "drag";
  case ViscosityModel::Morris: return "morris";
  }
  return "?";
}

std::string toString(Integrator integrator) {
  switch (integrator) {
  case Integrator::CentralDifference: return "central-difference";
  case Integrator::Explicit: return "explicit";
  case Integrator::Overdamped: return "overdamped";
  }
  return "?";
}

std::string toString(FixedSumMethod method) {
  return method == FixedSumMethod::Exact ? "exact" : "tabulated";
}

FixedSumMethod parseFixedSumMethod(const std::string& name) {
  if (name == "exact") return FixedSumMethod::Exact;
  if (name == "tabulated") return FixedSumMethod::Tabulated;
  throw std::invalid_argument("unknown fixed-particle sum method '" + name + "' (expected exact or tabulated)");
}

ViscosityModel parseViscosityModel(const std::string& name) {
  if (name == "none") return ViscosityModel::None;
  if (name == "drag") return ViscosityModel::Drag;
  if (name == "morris") return ViscosityModel::Morris;
  throw std::invalid_argument("unknown viscosity model '" + name + "' (expected drag, morris or none)");
}

Integrator parseIntegrator(const std::string& name) {
  if (name == "central-difference" || name == "paper") return Integrator::CentralDifference;
  if (name == "explicit") return Integrator::Explicit;
  if (name == "overdamped") return Integrator::Overdamped;
  throw std::invalid_argument("unknown integrator '" + name +
                              "' (expected central-difference, explicit or overdamped)");
}

} // namespace cementsph::sph
