#include "PhantomTip.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace cementsph::testing {

std::string foamPhantomTipArgument(const std::filesystem::path& dataDir) {
  std::ifstream in(dataDir / "foam-phantom" / "truth.json");
  const auto tip = nlohmann::json::parse(in).at("injection").at("tip_mm");
  std::ostringstream s;
  s.precision(17);
  s << tip[0].get<double>() << "," << tip[1].get<double>() << "," << tip[2].get<double>();
  return s.str();
}

} // namespace cementsph::testing
