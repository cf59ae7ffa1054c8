// The bundled foam phantom's injection tip (Data/foam-phantom/truth.json, "injection.tip_mm") as the
// x,y,z text a --tip-mm option takes, every digit kept.
#pragma once

#include <filesystem>
#include <string>

namespace cementsph::testing {

std::string foamPhantomTipArgument(const std::filesystem::path& dataDir);

} // namespace cementsph::testing
