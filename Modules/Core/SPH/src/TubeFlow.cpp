#include "cementsph/sph/TubeFlow.h"

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace cementsph::sph {

namespace {
constexpr double kPi = 3.14159265358979323846;

// Nominal inner diameters [mm], regular wall (needle gauge chart, after ISO 9626 / Birmingham gauge:
// 8G OD 4.191 ID 3.429, 10G 3.404 / 2.692, 11G 3.048 / 2.388, 12G 2.769 / 2.159, 13G 2.413 / 1.803);
// thin wall 10G ID 0.112-0.116 in (2.896 mm nominal, hypodermic tubing suppliers). Other thin walls are not
// tabulated here: give cannula_inner_diameter_mm.
const std::vector<std::pair<std::string, double>>& gauges() {
  static const std::vector<std::pair<std::string, double>> table{
      {"8G", 3.429}, {"10G", 2.692}, {"10G-thin", 2.896}, {"11G", 2.388}, {"12G", 2.159}, {"13G", 1.803}};
  return table;
}

void requirePositive(double x, const char* what) {
  if (!(x > 0) || !std::isfinite(x)) throw std::invalid_argument(std::string(what) + " must be a positive number");
}

// Shear rate at stress tau: tau = mu(g) g rises with g; bisection on log g.
double shearRateAtStress(const Rheology& law, double tau) {
  if (tau <= 0) return 0.0;
  double lo = 0.0, hi = 1.0;
  while (law.viscosity(hi) * hi < tau && hi < 1e15) hi *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (law.viscosity(mid) * mid < tau) lo = mid;
    else hi = mid;
    if (hi - lo <= 1e-13 * hi) break;
  }
  return 0.5 * (lo + hi);
}

// Q(tau_w) = pi R^3 / tau_w^3 * integral_0^tau_w tau^2 gamma_dot(tau) dtau (Simpson, 400 intervals).
double flowAtWallStress(const Rheology& law, double tauW, double R) {
  const int n = 400;
  double sum = 0;
  for (int i = 0; i <= n; ++i) {
    const double tau = tauW * double(i) / n;
    const double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
    sum += w * tau * tau * shearRateAtStress(law, tau);
  }
  const double integral = sum * tauW / (3.0 * n);
  return kPi * R * R * R / (tauW * tauW * tauW) * integral;
}
} // namespace

double powerLawTubePressureDrop(double K, double n, double L, double Q, double D) {
  requirePositive(K, "consistency");
  requirePositive(n, "flow index");
  requirePositive(L, "length");
  requirePositive(Q, "flow rate");
  requirePositive(D, "diameter");
  const double R = 0.5 * D;
  return 2.0 * K * L / R * std::pow((3.0 * n + 1.0) / n * Q / (kPi * R * R * R), n);
}

double powerLawConsistency(double dp, double n, double L, double Q, double D) {
  requirePositive(dp, "pressure drop");
  return dp / powerLawTubePressureDrop(1.0, n, L, Q, D);
}

double tubePressureDrop(const Rheology& law, double L, double Q, double D) {
  requirePositive(L, "length");
  requirePositive(Q, "flow rate");
  requirePositive(D, "diameter");
  const double R = 0.5 * D;
  double lo = 0.0, hi = 1.0;
  while (flowAtWallStress(law, hi, R) < Q && hi < 1e15) hi *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (flowAtWallStress(law, mid, R) < Q) lo = mid;
    else hi = mid;
    if (hi - lo <= 1e-11 * hi) break;
  }
  return 2.0 * L * 0.5 * (lo + hi) / R;
}

double cannulaInnerDiameterMm(const std::string& gauge) {
  for (const auto& [name, id] : gauges())
    if (name == gauge) return id;
  throw std::invalid_argument("unknown cannula gauge '" + gauge + "' (known: " + knownCannulaGauges() +
                              "; or give the inner diameter in mm)");
}

std::string knownCannulaGauges() {
  std::string s;
  for (const auto& [name, id] : gauges()) s += (s.empty() ? "" : ", ") + name;
  return s;
}

} // namespace cementsph::sph
