// Moved to the Rheology module (Modules/Core/Rheology, namespace cementsph::rheology), which both injection
// engines use; this header keeps code written against cementsph::sph compiling. New code includes
// "cementsph/rheology/Rheology.h".
#pragma once

#include "cementsph/rheology/Rheology.h"

namespace cementsph::sph {
using rheology::RheologyParameters;
using rheology::Rheology;
using rheology::makeRheology;
using rheology::rheologyNames;
using rheology::darcyShearRate;
} // namespace cementsph::sph
