#include "cementsph/rheology/ViscositySchedule.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cementsph::rheology {

namespace {
void requirePositiveViscosity(double mu, const std::string& where) {
  if (!(std::isfinite(mu) && mu > 0)) {
    std::ostringstream s;
    s << where << ": viscosity must be positive and finite, got " << mu << " Pa.s";
    throw std::invalid_argument(s.str());
  }
}
} // namespace

ViscositySchedule ViscositySchedule::constant(double viscosityPaS) {
  requirePositiveViscosity(viscosityPaS, "constant viscosity schedule");
  ViscositySchedule s;
  s.kind_ = Kind::Constant;
  s.mu0_ = viscosityPaS;
  return s;
}

ViscositySchedule ViscositySchedule::linear(double initialViscosityPaS, double ratePaSPerS) {
  requirePositiveViscosity(initialViscosityPaS, "linear viscosity schedule");
  if (!(std::isfinite(ratePaSPerS) && ratePaSPerS >= 0)) {
    std::ostringstream s;
    s << "linear viscosity schedule: the rate must be zero or positive and finite (curing cement thickens), got "
      << ratePaSPerS << " Pa.s/s";
    throw std::invalid_argument(s.str());
  }
  ViscositySchedule s;
  s.kind_ = Kind::Linear;
  s.mu0_ = initialViscosityPaS;
  s.rate_ = ratePaSPerS;
  return s;
}

ViscositySchedule ViscositySchedule::table(std::vector<std::pair<double, double>> points) {
  if (points.empty()) throw std::invalid_argument("viscosity table: needs at least one (time, viscosity) point");
  for (std::size_t k = 0; k < points.size(); ++k) {
    const auto [t, mu] = points[k];
    if (!std::isfinite(t)) {
      std::ostringstream s;
      s << "viscosity table: time of point " << k << " is not finite";
      throw std::invalid_argument(s.str());
    }
    requirePositiveViscosity(mu, "viscosity table, point " + std::to_string(k));
    if (k > 0 && !(t > points[k - 1].first)) {
      std::ostringstream s;
      s << "viscosity table: times must increase strictly, but point " << k << " (t = " << t
        << " s) does not come after point " << k - 1 << " (t = " << points[k - 1].first << " s)";
      throw std::invalid_argument(s.str());
    }
  }
  ViscositySchedule s;
  s.kind_ = Kind::Table;
  s.points_ = std::move(points);
  return s;
}

double ViscositySchedule::at(double timeS) const {
  switch (kind_) {
  case Kind::Constant: return mu0_;
  case Kind::Linear: return mu0_ + rate_ * std::max(0.0, timeS);
  case Kind::Table: {
    if (timeS <= points_.front().first) return points_.front().second; // clamped before the first point
    if (timeS >= points_.back().first) return points_.back().second;   // and after the last
    const auto upper = std::upper_bound(points_.begin(), points_.end(), timeS,
                                        [](double t, const std::pair<double, double>& p) { return t < p.first; });
    const auto lower = upper - 1;
    const double w = (timeS - lower->first) / (upper->first - lower->first);
    return lower->second + w * (upper->second - lower->second);
  }
  }
  return mu0_;
}

} // namespace cementsph::rheology
