// Viscosity laws and the cannula's pressure drop (issue "Cement rheology"). Oracles:
//  * the power law's tube drop against the closed form written out here, dp = 2 K L / R ((3n+1)/n Q/(pi R^3))^n,
//    to 1e-9, and n = 1 against Eq. 13 (Hagen-Poiseuille);
//  * the general Rabinowitsch-Mooney route (numerical) against that closed form, and a Carreau cement with
//    lambda = 0 against Hagen-Poiseuille at its mu0;
//  * the laws' values at chosen shear rates, their bounds, and the gauge table's 11G (the paper's 2.388 mm).
#include "cementsph/sph/HagenPoiseuille.h"
#include "cementsph/sph/TubeFlow.h"
#include "cementsph/sph/Viscosity/Rheology.h"

#include <gtest/gtest.h>

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

TEST(Rheology, CannulaGauges) {
  EXPECT_DOUBLE_EQ(cannulaInnerDiameterMm("11G"), 2.388);
  EXPECT_DOUBLE_EQ(cannulaInnerDiameterMm("8G"), 3.429);
  EXPECT_DOUBLE_EQ(cannulaInnerDiameterMm("13G"), 1.803);
  EXPECT_THROW(cannulaInnerDiameterMm("7G"), std::invalid_argument);
}
