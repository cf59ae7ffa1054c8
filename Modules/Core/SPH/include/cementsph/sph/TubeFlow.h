// Pressure drop of a generalised Newtonian cement in a cannula (issue "Cement rheology", item 3), and the
// cannulas by gauge.
//  * Power law: the exact Rabinowitsch-Mooney result, dp = 2 K L / R ((3n + 1) / n Q / (pi R^3))^n
//    (n = 1: Hagen-Poiseuille, Eq. 13).
//  * Any law: the Rabinowitsch-Mooney relation Q = pi R^3 / tau_w^3 * integral_0^tau_w tau^2 gamma_dot(tau)
//    dtau, solved for the wall stress tau_w (gamma_dot(tau) inverts tau = mu(gamma_dot) gamma_dot, which rises
//    monotonically for the laws here), dp = 2 L tau_w / R. Bisection and Simpson's rule, relative 1e-10.
#pragma once

#include "cementsph/sph/Viscosity/Rheology.h"

#include <string>

namespace cementsph::sph {

double powerLawTubePressureDrop(double consistencyPaSn, double flowIndex, double lengthM, double flowRateM3PerS,
                                double diameterM);
// K [Pa s^n] from a measured drop at a given n (the inverse of the above).
double powerLawConsistency(double pressureDropPa, double flowIndex, double lengthM, double flowRateM3PerS,
                           double diameterM);
// Any law (bounded, as Rheology::viscosity), by the Rabinowitsch-Mooney relation.
double tubePressureDrop(const Rheology& law, double lengthM, double flowRateM3PerS, double diameterM);

// Inner diameter [mm] of a cannula gauge: "8G" ... "13G" (regular wall, nominal), "10G-thin" (thin wall);
// throws std::invalid_argument naming the gauges known. Sources in docs (VALIDATION.md, cannulas).
double cannulaInnerDiameterMm(const std::string& gauge);
std::string knownCannulaGauges();

} // namespace cementsph::sph
