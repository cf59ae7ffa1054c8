// Moved to the Rheology module (Modules/Core/Rheology, namespace cementsph::rheology), which both injection
// engines use; this header keeps code written against cementsph::sph compiling. New code includes
// "cementsph/rheology/TubeFlow.h".
#pragma once

#include "cementsph/rheology/TubeFlow.h"

namespace cementsph::sph {
using rheology::powerLawTubePressureDrop;
using rheology::powerLawConsistency;
using rheology::tubePressureDrop;
using rheology::cannulaInnerDiameterMm;
using rheology::canonicalCannulaGauge;
using rheology::knownCannulaGauges;
} // namespace cementsph::sph
