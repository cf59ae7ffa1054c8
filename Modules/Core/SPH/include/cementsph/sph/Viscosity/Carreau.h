// Moved to the Rheology module (Modules/Core/Rheology, namespace cementsph::rheology), which both injection
// engines use; this header keeps code written against cementsph::sph compiling. New code includes
// "cementsph/rheology/Carreau.h".
#pragma once

#include "cementsph/rheology/Carreau.h"

namespace cementsph::sph {
using rheology::Carreau;
} // namespace cementsph::sph
