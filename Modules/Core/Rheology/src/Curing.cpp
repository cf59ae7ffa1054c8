#include "cementsph/rheology/Curing.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cementsph::rheology {

const std::vector<BundledCement>& bundledCements() {
  // Nicholas et al. 2007 (Curing.h): 8.7 and 13 min at 25 C, about half at 37 C; 75e3 Pa s for all.
  static const std::vector<BundledCement> cements{
      {"cmw1-25c", 8.7 * 60, 75e3, 25, false},           {"palacos-r-25c", 13 * 60, 75e3, 25, false},
      {"cemex-isoplastic-25c", 13 * 60, 75e3, 25, false}, {"cmw1-37c", 8.7 * 30, 75e3, 37, true},
      {"palacos-r-37c", 13 * 30, 75e3, 37, true},         {"cemex-isoplastic-37c", 13 * 30, 75e3, 37, true}};
  return cements;
}

std::string knownCements() {
  std::string s;
  for (const BundledCement& c : bundledCements()) s += (s.empty() ? "" : ", ") + c.name;
  return s;
}

const BundledCement& bundledCement(const std::string& name) {
  for (const BundledCement& c : bundledCements())
    if (c.name == name) return c;
  throw std::invalid_argument("unknown cement \"" + name + "\" (bundled: " + knownCements() + ")");
}

CuringCurve CuringCurve::none() { return CuringCurve{}; }

CuringCurve CuringCurve::table(std::vector<std::pair<double, double>> rows) {
  if (rows.empty()) throw std::invalid_argument("curing table: no rows");
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (!(rows[k].second > 0) || !std::isfinite(rows[k].second)) throw std::invalid_argument("curing table: factors must be > 0");
    if (k > 0 && !(rows[k].first > rows[k - 1].first)) throw std::invalid_argument("curing table: times must increase strictly");
  }
  CuringCurve c;
  c.kind_ = "table";
  c.rows_ = std::move(rows);
  return c;
}

CuringCurve CuringCurve::exponential(double tRef, double muRef, double tCure, double muCured) {
  auto finite = [](double x) { return std::isfinite(x); };
  if (!(finite(tRef) && finite(muRef) && finite(tCure) && finite(muCured)))
    throw std::invalid_argument("exponential curing: times and viscosities must be finite");
  if (!(tRef >= 0 && tCure > tRef)) {
    std::ostringstream s;
    s << "exponential curing: the curing time (" << tCure << " s since mixing) must come after the reference time ("
      << tRef << " s, >= 0)";
    throw std::invalid_argument(s.str());
  }
  if (!(muRef > 0 && muCured > muRef)) {
    std::ostringstream s;
    s << "exponential curing: the cured viscosity (" << muCured << " Pa s) must exceed the law's viscosity at the "
      << "reference time (" << muRef << " Pa s, > 0)";
    throw std::invalid_argument(s.str());
  }
  CuringCurve c;
  c.kind_ = "exponential";
  c.referenceTimeS_ = tRef;
  c.curingTimeS_ = tCure;
  c.maxFactor_ = muCured / muRef;
  c.tau_ = (tCure - tRef) / std::log(c.maxFactor_);
  return c;
}

double CuringCurve::factor(double t) const {
  if (kind_ == "exponential") return t >= curingTimeS_ ? maxFactor_ : std::exp((t - referenceTimeS_) / tau_);
  if (kind_ != "table") return 1.0;
  if (t <= rows_.front().first) return rows_.front().second;
  for (std::size_t k = 1; k < rows_.size(); ++k)
    if (t <= rows_[k].first) {
      const auto& [t0, f0] = rows_[k - 1];
      const auto& [t1, f1] = rows_[k];
      return f0 + (f1 - f0) * (t - t0) / (t1 - t0);
    }
  return rows_.back().second;
}

} // namespace cementsph::rheology
