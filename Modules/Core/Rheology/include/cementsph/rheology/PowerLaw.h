// Power-law (Ostwald-de Waele) cement: mu = K gamma_dot^(n - 1), K the consistency [Pa s^n], n the flow index
// (n < 1 shear-thinning: PMMA cements, the paper's "usually captured using a power law").
#pragma once

#include "cementsph/rheology/Rheology.h"

#include <cmath>

namespace cementsph::rheology {

class PowerLaw : public Rheology {
public:
  PowerLaw(double consistencyPaSn, double flowIndex) : k_(consistencyPaSn), n_(flowIndex) {}
  std::string name() const override { return "power-law"; }
  double unbounded(double gammaDot) const override { return k_ * std::pow(gammaDot, n_ - 1.0); }
  double flowIndex() const override { return n_; }
  double consistency() const { return k_; }

private:
  double k_, n_;
};

} // namespace cementsph::rheology
