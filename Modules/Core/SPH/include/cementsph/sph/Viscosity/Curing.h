// Moved to the Rheology module (Modules/Core/Rheology, namespace cementsph::rheology), which both injection
// engines use; this header keeps code written against cementsph::sph compiling. New code includes
// "cementsph/rheology/Curing.h".
#pragma once

#include "cementsph/rheology/Curing.h"

namespace cementsph::sph {
using rheology::BundledCement;
using rheology::bundledCements;
using rheology::bundledCement;
using rheology::knownCements;
using rheology::CuringCurve;
} // namespace cementsph::sph
