// Viscosity laws and the cannula's pressure drop (issue "Cement rheology"). Oracles:
//  * the power law's tube drop against the closed form written out here, dp = 2 K L / R ((3n+1)/n Q/(pi R^3))^n,
//    to 1e-9, and n = 1 against Eq. 13 (Hagen-Poiseuille);
//  * the general Rabinowitsch-Mooney route (numerical) against that closed form, and a Carreau cement with
//    lambda = 0 against Hagen-Poiseuille at its mu0;
//  * the laws' values at chosen shear rates, their bounds, and the gauge table's 11G (the paper's 2.388 mm).
#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/TubeFlow.h"
#include "cementsph/sph/Viscosity/Curing.h"
#include "cementsph/sph/Viscosity/Rheology.h"

#include <gtest/gtest.h>

#include <tuple>
#include <vector>

#include <cmath>

using namespace cementsph::sph;

namespace {
constexpr double kPi = 3.14159265358979323846;
const double L = 0.09, Q = 0.05e-6, D = 2.388e-3; // the paper's 11G, 9 cm cannula at 0.05 ml/s
} // namespace

TEST(Rheology, PowerLawTubeDropIsRabinowitschMooneysClosedForm) {
  for (double n : {0.3, 0.5, 0.8, 1.2}) {
    const double K = 250.0, R = 0.5 * D;
    const double expected = 2 * K * L / R * std::pow((3 * n + 1) / n * Q / (kPi * R * R * R), n);
    EXPECT_NEAR(powerLawTubePressureDrop(K, n, L, Q, D) / expected, 1.0, 1e-9) << n;
    EXPECT_NEAR(powerLawConsistency(expected, n, L, Q, D) / K, 1.0, 1e-9) << n;
  }
  EXPECT_NEAR(powerLawTubePressureDrop(100.0, 1.0, L, Q, D) / hagenPoiseuillePressureDrop(100.0, L, Q, D), 1.0, 1e-12);
}

TEST(Rheology, TheGeneralTubeIntegralAgreesWithTheClosedFormsItIsNotBuiltOn) {
  RheologyParameters p;
  p.minimumViscosityPaS = 1e-9;
  p.maximumViscosityPaS = 1e12;
  for (double n : {0.4, 1.0}) {
    p.consistencyPaSn = 300.0;
    p.flowIndex = n;
    const auto law = makeRheology("power-law", p);
    EXPECT_NEAR(tubePressureDrop(*law, L, Q, D) / powerLawTubePressureDrop(300.0, n, L, Q, D), 1.0, 1e-6) << n;
  }
  p.zeroShearViscosityPaS = 150.0;
  p.timeConstantS = 0.0; // Newtonian at mu0
  p.flowIndex = 0.5;
  const auto carreau = makeRheology("carreau", p);
  EXPECT_NEAR(tubePressureDrop(*carreau, L, Q, D) / hagenPoiseuillePressureDrop(150.0, L, Q, D), 1.0, 1e-6);
}

TEST(Rheology, LawsTheirBoundsAndTheDarcyShearRate) {
  RheologyParameters p;
  p.consistencyPaSn = 200.0;
  p.flowIndex = 0.5;
  p.minimumViscosityPaS = 1.0;
  p.maximumViscosityPaS = 1000.0;
  const auto power = makeRheology("power-law", p);
  EXPECT_NEAR(power->viscosity(4.0), 200.0 / 2.0, 1e-12);       // K 4^(-1/2)
  EXPECT_DOUBLE_EQ(power->viscosity(0.0), 1000.0);               // 0^(n-1) = inf: the upper bound
  EXPECT_DOUBLE_EQ(power->viscosity(1e12), 1.0);                 // the lower bound
  p.zeroShearViscosityPaS = 500.0;
  p.infiniteShearViscosityPaS = 0.0;
  p.timeConstantS = 2.0;
  const auto carreau = makeRheology("carreau", p);
  EXPECT_NEAR(carreau->viscosity(0.0), 500.0, 1e-12);
  EXPECT_NEAR(carreau->viscosity(1.5), 500.0 * std::pow(1.0 + 9.0, -0.25), 1e-9); // (1 + (2 * 1.5)^2)^((n-1)/2)
  // Christopher-Middleman: (3n+1)/(4n) 12 q / sqrt(150 k phi); n = 1: 12 / sqrt(150) q / sqrt(k phi).
  EXPECT_NEAR(darcyShearRate(1e-3, 1e-8, 0.5, 1.0), 12.0 / std::sqrt(150.0) * 1e-3 / std::sqrt(0.5e-8), 1e-9);
  p.flowIndex = 0.0;
  EXPECT_THROW(makeRheology("power-law", p), std::invalid_argument);
  EXPECT_THROW(makeRheology("bingham", p), std::invalid_argument);
}

TEST(Rheology, CannulaGaugesAreTheSourcesNominalInnerDiameters) {
  // The sources' numbers (TubeFlow.h): regular wall the needle gauge chart's mm column [1] (and its inches,
  // to the chart's rounding); 10G thin and extra-thin the midpoints of Component Supply's inch ranges [3]
  // (0.112-0.116, 0.1165-0.120 in).
  const double in = 25.4;
  const std::vector<std::tuple<const char*, double, double>> chart{
      {"8G", 3.429, 0.135}, {"10G", 2.692, 0.106}, {"11G", 2.388, 0.094}, {"12G", 2.159, 0.085}, {"13G", 1.803, 0.071}};
  for (const auto& [name, mm, inches] : chart) {
    EXPECT_DOUBLE_EQ(cannulaInnerDiameterMm(name), mm) << name;
    EXPECT_NEAR(cannulaInnerDiameterMm(name), inches * in, 0.0005) << name;
  }
  EXPECT_NEAR(cannulaInnerDiameterMm("10G-thin"), 0.5 * (0.112 + 0.116) * in, 1e-12);
  EXPECT_NEAR(cannulaInnerDiameterMm("10G-extra-thin"), 0.5 * (0.1165 + 0.120) * in, 1e-12);
  // A second chart [2] gives 8 RW ID 3.43 mm (to its 0.01 mm) and 10G RW within [3]'s 0.104-0.108 in.
  EXPECT_NEAR(cannulaInnerDiameterMm("8G"), 3.43, 0.005);
  EXPECT_GE(cannulaInnerDiameterMm("10G"), 0.104 * in);
  EXPECT_LE(cannulaInnerDiameterMm("10G"), 0.108 * in);
  // The accepted spellings of one cannula, and the canonical names.
  for (const char* name : {"10GTW", "10g-tw", "10G TW", "10G-thin", "10G_THIN"}) {
    EXPECT_NEAR(cannulaInnerDiameterMm(name), 0.114 * in, 1e-12) << name;
    EXPECT_EQ(canonicalCannulaGauge(name), "10G-thin") << name;
  }
  EXPECT_EQ(canonicalCannulaGauge("10gxtw"), "10G-extra-thin");
  EXPECT_EQ(canonicalCannulaGauge("11G-RW"), "11G");
  EXPECT_EQ(knownCannulaGauges(), "8G, 10G, 10G-thin, 10G-extra-thin, 11G, 12G, 13G");
  // Unknown names: one line listing the valid names. A known gauge without a sourced thin wall: says so.
  const auto errorOf = [](const char* name) -> std::string {
    try {
      (void)cannulaInnerDiameterMm(name);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no error";
  };
  for (const char* bad : {"7G", "9G", "11", "G", "11G-ultra", "111G", ""}) {
    const std::string what = errorOf(bad);
    EXPECT_NE(what.find("valid: 8G, 10G, 10G-thin"), std::string::npos) << bad << ": " << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  for (const char* noSource : {"11G-thin", "11GTW", "13G-thin", "8GTW", "12G-extra-thin"}) {
    const std::string what = errorOf(noSource);
    EXPECT_NE(what.find("no sourced"), std::string::npos) << noSource << ": " << what;
    EXPECT_NE(what.find("give the inner diameter"), std::string::npos) << what;
  }
}

TEST(Curing, BundledCementsAreNicholas2007sFigures) {
  // Nicholas et al. 2007 (abstract): 25 C, CMW 1 cures in 8.7 min, Palacos R and Cemex ISOPLASTIC in 13 min;
  // curing rates about halved at 37 C (so half the times, approximate); 75e3 Pa s maximum for all three.
  const std::vector<std::tuple<const char*, double, double, bool>> expected{
      {"cmw1-25c", 8.7 * 60, 25, false},   {"palacos-r-25c", 13 * 60, 25, false},
      {"cemex-isoplastic-25c", 13 * 60, 25, false}, {"cmw1-37c", 8.7 * 60 / 2, 37, true},
      {"palacos-r-37c", 13 * 60 / 2, 37, true},     {"cemex-isoplastic-37c", 13 * 60 / 2, 37, true}};
  ASSERT_EQ(bundledCements().size(), expected.size());
  for (const auto& [name, seconds, celsius, approximate] : expected) {
    const BundledCement& c = bundledCement(name);
    EXPECT_NEAR(c.curingTimeS, seconds, 1e-9) << name;
    EXPECT_EQ(c.curedViscosityPaS, 75e3) << name;
    EXPECT_EQ(c.temperatureC, celsius) << name;
    EXPECT_EQ(c.approximate, approximate) << name;
  }
  try {
    (void)bundledCement("simplex-p");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bundled: cmw1-25c, palacos-r-25c"), std::string::npos) << e.what();
  }
}

TEST(Curing, TheExponentialPassesThroughItsTwoPointsAndHoldsTheCuredViscosity) {
  // mu_ref 100 Pa s at 120 s after mixing; CMW 1 at 25 C: 75e3 Pa s at 522 s (Nicholas 2007).
  const double tRef = 120, muRef = 100, tCure = 522, muCured = 75e3;
  const CuringCurve c = CuringCurve::exponential(tRef, muRef, tCure, muCured);
  EXPECT_EQ(c.kind(), "exponential");
  const double tau = (tCure - tRef) / std::log(muCured / muRef); // written out: 402 s / ln 750
  EXPECT_NEAR(c.timeConstantS(), tau, 1e-12 * tau);
  EXPECT_NEAR(c.factor(tRef), 1.0, 1e-12);
  EXPECT_NEAR(muRef * c.factor(tCure), 75e3, 1e-9 * 75e3);                      // the source's cured viscosity
  EXPECT_NEAR(c.factor(0.5 * (tRef + tCure)), std::sqrt(750.0), 1e-9);          // halfway: the geometric mean
  EXPECT_NEAR(c.factor(300.0), std::exp(180.0 / tau), 1e-12 * c.factor(300.0)); // 300 s after mixing
  EXPECT_NEAR(c.factor(0.0), std::exp(-120.0 / tau), 1e-12);                    // earlier: thinner
  EXPECT_EQ(c.factor(2000.0), 750.0);                                           // held once cured
  // Table: piecewise linear, held outside.
  const CuringCurve t = CuringCurve::table({{0.0, 1.0}, {100.0, 3.0}});
  EXPECT_DOUBLE_EQ(t.factor(25.0), 1.5);
  EXPECT_DOUBLE_EQ(t.factor(-5.0), 1.0);
  EXPECT_DOUBLE_EQ(t.factor(500.0), 3.0);
  EXPECT_EQ(CuringCurve::none().factor(1e6), 1.0);
  // Out of range: one line each.
  EXPECT_THROW(CuringCurve::exponential(600, 100, 522, 75e3), std::invalid_argument); // cured before the reference
  EXPECT_THROW(CuringCurve::exponential(0, 1e5, 522, 75e3), std::invalid_argument);   // cured below the reference
  EXPECT_THROW(CuringCurve::exponential(-1, 100, 522, 75e3), std::invalid_argument);
  EXPECT_THROW(CuringCurve::table({{0.0, 1.0}, {0.0, 2.0}}), std::invalid_argument);
}
