// Moved to the Rheology module (Modules/Core/Rheology, namespace cementsph::rheology), which both injection
// engines use; this header keeps code written against cementsph::sph compiling. New code includes
// "cementsph/rheology/HagenPoiseuille.h".
#pragma once

#include "cementsph/rheology/HagenPoiseuille.h"

namespace cementsph::sph {
using rheology::hagenPoiseuillePressureDrop;
using rheology::hagenPoiseuilleViscosity;
using rheology::boreSpeed;
} // namespace cementsph::sph
