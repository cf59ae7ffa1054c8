// Pressure drop of a generalised Newtonian cement in a cannula (issue "Cement rheology", item 3), and the
// cannulas by gauge.
//  * Power law: the exact Rabinowitsch-Mooney result, dp = 2 K L / R ((3n + 1) / n Q / (pi R^3))^n
//    (n = 1: Hagen-Poiseuille, Eq. 13).
//  * Any law: the Rabinowitsch-Mooney relation Q = pi R^3 / tau_w^3 * integral_0^tau_w tau^2 gamma_dot(tau)
//    dtau, solved for the wall stress tau_w (gamma_dot(tau) inverts tau = mu(gamma_dot) gamma_dot, which rises
//    monotonically for the laws here), dp = 2 L tau_w / R. Bisection and Simpson's rule, relative 1e-10.
#pragma once

#include "cementsph/rheology/Rheology.h"

#include <string>

namespace cementsph::rheology {

double powerLawTubePressureDrop(double consistencyPaSn, double flowIndex, double lengthM, double flowRateM3PerS,
                                double diameterM);
// K [Pa s^n] from a measured drop at a given n (the inverse of the above).
double powerLawConsistency(double pressureDropPa, double flowIndex, double lengthM, double flowRateM3PerS,
                           double diameterM);
// Any law (bounded, as Rheology::viscosity), by the Rabinowitsch-Mooney relation.
double tubePressureDrop(const Rheology& law, double lengthM, double flowRateM3PerS, double diameterM);

// Cannulas by gauge (issue 11). Names, case-insensitive, spaces ignored: "<N>G" is regular wall (also
// "<N>G-RW", "<N>GRW"); "<N>G-thin" / "<N>GTW" / "<N>G-TW" thin wall; "<N>G-extra-thin" / "<N>GXTW" /
// "<N>G-XTW" extra-thin wall. The canonical names are "11G", "11G-thin", "10G-extra-thin".
// The table (all figures NOMINAL, none is a minimum; [1] gives inches and mm, [3] inches only):
//   wall     gauge  OD [in]  ID [in]   ID [mm]  source
//   regular  8      0.165    0.135     3.429    [1]; [2] 8 RW: OD 4.19, ID 3.43 (3.35/3.51) mm
//   regular  10     0.134    0.106     2.692    [1]; [3] RW ID 0.104-0.108 in (midpoint 0.106)
//   regular  11     0.120    0.094     2.388    [1] (the paper's 11G cannula)
//   regular  12     0.109    0.085     2.159    [1]
//   regular  13     0.095    0.071     1.803    [1]
//   thin     10     0.134    0.114     2.8956   [3] TW ID 0.112-0.116 in: the midpoint
//   x-thin   10     0.134    0.11825   3.00355  [3] XTW ID 0.1165-0.120 in: the midpoint
// ID tolerance +-0.003 in (+-0.076 mm) for 7-14 G in [1].
// [1] Needle gauge comparison chart (nominal OD, ID, wall; regular wall), en.wikipedia.org/wiki/
//     Needle_gauge_comparison_chart; the Stubs (Birmingham) needle gauge.
// [2] New England Small Tube, metric hypodermic tubing chart (nesmalltube.com, Metric_Chart_Web.pdf).
// [3] Component Supply Co., "Information to remember when ordering hypodermic tube" (10 gauge: OD 0.133-0.135
//     in; ID regular 0.104-0.108, thin 0.112-0.116, extra-thin 0.1165-0.120 in).
// Not tabulated: thin walls of 8, 11, 12 and 13 G. No source at hand gives them (ISO 9626:2016 tabulates
// MINIMUM inner diameters per wall for 10-34 G but its table could not be read here; US thin-wall sizes
// also differ from ISO's, K-Tube's note): such a name is a clear error asking for the inner diameter.
//
// Inner diameter [mm] of a gauge by any accepted name. Throws std::invalid_argument, one line: for an unknown
// name it lists the valid names; for a known gauge whose wall is not tabulated it says so.
double cannulaInnerDiameterMm(const std::string& gauge);
// The canonical name of an accepted name ("11gtw" -> "11G-thin"); throws as above.
std::string canonicalCannulaGauge(const std::string& gauge);
// "8G, 10G, 10G-thin, 10G-extra-thin, 11G, 12G, 13G".
std::string knownCannulaGauges();

} // namespace cementsph::rheology
