#include "cementsph/rheology/TubeFlow.h"

#include <cctype>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace cementsph::rheology {

namespace {
constexpr double kPi = 3.14159265358979323846;

constexpr double kMmPerInch = 25.4;

// The gauge table of TubeFlow.h: nominal inner diameters [mm], the chart's own mm figures for regular walls,
// the supplier's inch ranges' midpoints converted for 10G thin and extra-thin.
struct Cannula {
  int gauge;
  const char* wall; // "" regular, "thin", "extra-thin"
  double innerDiameterMm;
};
const std::vector<Cannula>& cannulas() {
  static const std::vector<Cannula> table{{8, "", 3.429},
                                          {10, "", 2.692},
                                          {10, "thin", 0.114 * kMmPerInch},
                                          {10, "extra-thin", 0.11825 * kMmPerInch},
                                          {11, "", 2.388},
                                          {12, "", 2.159},
                                          {13, "", 1.803}};
  return table;
}

std::string nameOf(int gauge, const std::string& wall) {
  return std::to_string(gauge) + "G" + (wall.empty() ? "" : "-" + wall);
}

// Parses an accepted name into (gauge, wall); throws listing the valid names.
std::pair<int, std::string> parseGauge(const std::string& name) {
  std::string s;
  for (char c : name)
    if (!std::isspace(static_cast<unsigned char>(c))) s += char(std::toupper(static_cast<unsigned char>(c)));
  const auto unknown = [&]() {
    return std::invalid_argument("unknown cannula gauge '" + name + "' (valid: " + knownCannulaGauges() +
                                 "; thin wall also as 10GTW, extra-thin as 10GXTW; or give the inner diameter in mm)");
  };
  std::size_t digits = 0;
  while (digits < s.size() && std::isdigit(static_cast<unsigned char>(s[digits]))) ++digits;
  if (digits == 0 || digits > 2 || digits >= s.size() || s[digits] != 'G') throw unknown();
  const int gauge = std::stoi(s.substr(0, digits));
  std::string suffix = s.substr(digits + 1);
  if (!suffix.empty() && (suffix[0] == '-' || suffix[0] == '_')) suffix.erase(0, 1);
  std::string wall;
  if (suffix.empty() || suffix == "RW" || suffix == "REGULAR") wall = "";
  else if (suffix == "TW" || suffix == "THIN") wall = "thin";
  else if (suffix == "XTW" || suffix == "EXTRA-THIN" || suffix == "EXTRATHIN") wall = "extra-thin";
  else throw unknown();
  bool gaugeKnown = false;
  for (const Cannula& c : cannulas()) {
    if (c.gauge == gauge && c.wall == wall) return {gauge, wall};
    gaugeKnown = gaugeKnown || c.gauge == gauge;
  }
  if (!gaugeKnown) throw unknown();
  throw std::invalid_argument("cannula gauge '" + name + "': no sourced " + wall + "-wall inner diameter for " +
                              std::to_string(gauge) + "G (tabulated: " + knownCannulaGauges() +
                              "); give the inner diameter in mm instead");
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
  const auto [number, wall] = parseGauge(gauge);
  for (const Cannula& c : cannulas())
    if (c.gauge == number && c.wall == wall) return c.innerDiameterMm;
  throw std::logic_error("cannula table"); // parseGauge found it
}

std::string canonicalCannulaGauge(const std::string& gauge) {
  const auto [number, wall] = parseGauge(gauge);
  return nameOf(number, wall);
}

std::string knownCannulaGauges() {
  std::string s;
  for (const Cannula& c : cannulas()) s += (s.empty() ? "" : ", ") + nameOf(c.gauge, c.wall);
  return s;
}

} // namespace cementsph::rheology
