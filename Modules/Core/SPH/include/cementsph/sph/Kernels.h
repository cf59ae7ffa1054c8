// Smoothing kernels of Basafa et al. 2013. Both have compact support 2h (q = r/h <= 2).
//
//  * CubicSplineKernel, Eq. 10 (Monaghan's M4 in 3-D): used for density summation (Eq. 2),
//    for the Morris viscosity term (Eq. 7) and for voxelising particles into a CT.
//  * SpikyKernel, Eq. 11 (Desbrun & Gascuel 1996): its gradient does not vanish at r = 0, so the
//    pressure force (Eq. 5) keeps particles apart instead of letting them clump.
//
// Everything is inline: these functions sit in the innermost pair loops.
#pragma once

#include <cmath>

namespace cementsph::sph {

inline constexpr double kPi = 3.14159265358979323846;

class CubicSplineKernel {
public:
  explicit CubicSplineKernel(double h)
      : h_(h), invH_(1.0 / h), sigma_(1.0 / (kPi * h * h * h)) {}

  double h() const { return h_; }
  double support() const { return 2.0 * h_; }

  // W(r, h), Eq. 10.
  double value(double r) const {
    const double q = r * invH_;
    if (q >= 2.0) return 0.0;
    if (q > 1.0) {
      const double t = 2.0 - q;
      return sigma_ * 0.25 * t * t * t;
    }
    return sigma_ * (1.0 - 1.5 * q * q + 0.75 * q * q * q);
  }

  // dW/dr; the gradient is dW/dr * r_vec / r (and vanishes at r = 0).
  double derivative(double r) const {
    const double q = r * invH_;
    if (q >= 2.0) return 0.0;
    if (q > 1.0) {
      const double t = 2.0 - q;
      return -sigma_ * invH_ * 0.75 * t * t;
    }
    return sigma_ * invH_ * (-3.0 * q + 2.25 * q * q);
  }

  // (1/r) dW/dr, finite at r = 0 (limit -3 sigma / h^2): multiply by the pair vector to get grad W.
  double derivativeOverR(double r) const {
    const double q = r * invH_;
    if (q >= 2.0) return 0.0;
    if (q > 1.0) {
      const double t = 2.0 - q;
      return -sigma_ * invH_ * 0.75 * t * t / r;
    }
    return sigma_ * invH_ * invH_ * (-3.0 + 2.25 * q);
  }

private:
  double h_, invH_, sigma_;
};

class SpikyKernel {
public:
  explicit SpikyKernel(double h)
      : h_(h), invH_(1.0 / h), sigma_(15.0 / (kPi * 64.0 * h * h * h)) {}

  double h() const { return h_; }
  double support() const { return 2.0 * h_; }

  // W(r, h), Eq. 11: 15 / (pi (4h)^3) (2 - q)^3.
  double value(double r) const {
    const double q = r * invH_;
    if (q >= 2.0) return 0.0;
    const double t = 2.0 - q;
    return sigma_ * t * t * t;
  }

  // dW/dr = -3 sigma / h (2 - q)^2: non-zero (-12 sigma / h) at the origin.
  double derivative(double r) const {
    const double q = r * invH_;
    if (q >= 2.0) return 0.0;
    const double t = 2.0 - q;
    return -3.0 * sigma_ * invH_ * t * t;
  }

private:
  double h_, invH_, sigma_;
};

} // namespace cementsph::sph
