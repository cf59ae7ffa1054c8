// Curing of the cement (issue "Cement rheology", item 2): a viscosity factor over the time since mixing that
// multiplies the cement's law (the Newtonian viscosity, the power law's consistency K, Carreau's mu0 and
// mu_inf), so a curing cement keeps its shear-thinning index while it thickens. Three curves:
//  * none: factor 1;
//  * table: piecewise linear in (time since mixing [s], factor), held outside the table (scene curing_table);
//  * exponential: mu(t) = mu_ref exp((t - t_ref) / tau), through the law's viscosity mu_ref at t_ref since
//    mixing and the cured viscosity mu_cured at the curing time t_cure, tau = (t_cure - t_ref) / ln(mu_cured /
//    mu_ref); held at mu_cured after t_cure (the factor is mu(t) / mu_ref). Before t_ref it falls below 1.
//    The exponential form mu0 exp(t / tc) is our choice (two points fix it); no source's fitted time
//    constant is used, and between the two points the curve is a model, not a measurement.
// Bundled cements (bundledCement): the two points a cement needs besides mu_ref, from Nicholas et al. 2007
// (J Mater Sci: Mater Med, doi:10.1007/s10856-007-0125-2, "Analysis of rheological properties of bone cements", oscillating
// parallel-plate rheometer): at 25 C CMW 1 cures in 8.7 min, Palacos R and Cemex ISOPLASTIC in 13 min; at
// 37 C the curing rates are about halved (the abstract's words: the 37 C times below are half the 25 C ones,
// APPROXIMATE); all three reach the same maximum viscosity, 75e3 Pa s. Those are the abstract's figures; the
// paper's curves themselves were not at hand, so nothing here is read from a figure. The curing time is read
// as the time from the start of mixing to that maximum viscosity.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace cementsph::rheology {

struct BundledCement {
  std::string name;           // e.g. "cmw1-25c"
  double curingTimeS;         // from the start of mixing to the maximum viscosity [s]
  double curedViscosityPaS;   // the maximum viscosity [Pa s]
  double temperatureC;        // of the measurement
  bool approximate;           // true where the time is the abstract's "halved at 37 C"
};

const std::vector<BundledCement>& bundledCements();
// Throws std::invalid_argument (one line listing the names) for an unknown name.
const BundledCement& bundledCement(const std::string& name);
std::string knownCements(); // "cmw1-25c, palacos-r-25c, ..."

class CuringCurve {
public:
  static CuringCurve none();
  // Rows (time since mixing [s], factor > 0), times strictly increasing; throws std::invalid_argument.
  static CuringCurve table(std::vector<std::pair<double, double>> rows);
  // Throws std::invalid_argument (one line) unless 0 <= referenceTimeS < curingTimeS, 0 < referenceViscosityPaS
  // < curedViscosityPaS, all finite.
  static CuringCurve exponential(double referenceTimeS, double referenceViscosityPaS, double curingTimeS,
                                 double curedViscosityPaS);

  // The factor on the law's viscosity at a time since mixing [s].
  double factor(double timeSinceMixingS) const;
  const std::string& kind() const { return kind_; }
  double timeConstantS() const { return tau_; } // exponential only (0 otherwise)

private:
  std::string kind_ = "none";
  std::vector<std::pair<double, double>> rows_;
  double referenceTimeS_ = 0, curingTimeS_ = 0, tau_ = 0, maxFactor_ = 1;
};

} // namespace cementsph::rheology
