// Moved to the Rheology module (Modules/Core/Rheology, namespace cementsph::rheology), which both injection
// engines use; this header keeps code written against cementsph::sph compiling. New code includes
// "cementsph/rheology/PowerLaw.h".
#pragma once

#include "cementsph/rheology/PowerLaw.h"

namespace cementsph::sph {
using rheology::PowerLaw;
} // namespace cementsph::sph
