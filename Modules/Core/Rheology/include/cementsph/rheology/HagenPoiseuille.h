// Hagen-Poiseuille law, Basafa et al. 2013 Eq. 13: mu = pi D^4 dP / (128 L Q), and its inverse
// dP = 128 mu L Q / (pi D^4). The paper used it to estimate the cement viscosity from the syringe pressure,
// and to estimate the pressure "encountered by the cement upon exiting the cannula" (model-notes 4 gives the
// figures for the 11G 9 cm cannula and the 8G 16 cm pipette at 0.05 ml/s). SI units.
#pragma once

namespace cementsph::rheology {

// Pressure drop [Pa] over a tube of length L [m] and inner diameter D [m] at flow rate Q [m^3/s], viscosity mu [Pa.s].
double hagenPoiseuillePressureDrop(double viscosityPaS, double lengthM, double flowRateM3PerS, double diameterM);
// Viscosity [Pa.s] from a measured pressure drop (Eq. 13).
double hagenPoiseuilleViscosity(double pressureDropPa, double lengthM, double flowRateM3PerS, double diameterM);
// Mean speed in the bore, v0 = Q / (pi D^2 / 4) [m/s] (the paper's new-particle velocity).
double boreSpeed(double flowRateM3PerS, double diameterM);

} // namespace cementsph::rheology
