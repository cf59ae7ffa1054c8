// Models by name. Registration lives in ModelRegistry.cpp, one line per method (a static library would
// drop self-registering objects, so the list is explicit).
#pragma once

#include "cementsph/sph/ModelInterfaces.h"

#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace cementsph::sph {

struct ModelParameters;

template <class Interface> class Registry {
public:
  using Factory = std::function<std::unique_ptr<Interface>(const ModelParameters&)>;
  void add(const std::string& name, Factory f) { factories_[name] = std::move(f); }
  bool has(const std::string& name) const { return factories_.count(name) != 0; }
  std::unique_ptr<Interface> create(const std::string& name, const ModelParameters& p, const char* what) const {
    auto it = factories_.find(name);
    if (it == factories_.end()) {
      std::string known;
      for (const auto& [n, f] : factories_) known += (known.empty() ? "" : ", ") + n;
      throw std::invalid_argument(std::string("unknown ") + what + " '" + name + "' (expected one of: " + known + ")");
    }
    return it->second(p);
  }
  std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const auto& [name, f] : factories_) n.push_back(name);
    return n;
  }

private:
  std::map<std::string, Factory> factories_;
};

struct ModelRegistry {
  Registry<PressureModel> pressure;
  Registry<Resistance> resistance;
  Registry<ViscosityLaw> viscosity;
  Registry<TimeIntegrator> integrator;
  Registry<DomainBoundary> boundary;
  // The registry with every method of this build.
  static const ModelRegistry& instance();
};

} // namespace cementsph::sph
