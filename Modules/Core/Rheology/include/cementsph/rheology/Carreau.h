// Carreau cement (Carreau 1972, Trans. Soc. Rheol. 16:99): mu = mu_inf + (mu0 - mu_inf) (1 + (lambda
// gamma_dot)^2)^((n - 1) / 2): Newtonian mu0 at low shear, a power law of index n above 1 / lambda.
#pragma once

#include "cementsph/rheology/Rheology.h"

#include <cmath>

namespace cementsph::rheology {

class Carreau : public Rheology {
public:
  Carreau(double zeroShearPaS, double infiniteShearPaS, double timeConstantS, double flowIndex)
      : mu0_(zeroShearPaS), muInf_(infiniteShearPaS), lambda_(timeConstantS), n_(flowIndex) {}
  std::string name() const override { return "carreau"; }
  double unbounded(double gammaDot) const override {
    const double x = lambda_ * gammaDot;
    return muInf_ + (mu0_ - muInf_) * std::pow(1.0 + x * x, 0.5 * (n_ - 1.0));
  }
  double flowIndex() const override { return n_; }

private:
  double mu0_, muInf_, lambda_, n_;
};

} // namespace cementsph::rheology
