// Issue 21: `cementsph viscosity` on options whose result overflows or is undefined. Each run must exit 1
// with one line on stderr naming the options, and print nothing (no `inf`, no `null` in --json); a valid
// run prints the drop Hagen-Poiseuille gives, computed here from the formula (dP = 128 mu L Q / (pi D^4)).
#include "ProgramRun.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace {

using cementsph::testing::ProgramRun;

const std::string kProgram = std::string(CEMENTSPH_BINARY_DIR) + "/bin/cementsph";

ProgramRun viscosity(const std::vector<std::string>& args) {
  std::vector<std::string> all{"-k", "5", "60", kProgram, "viscosity"};
  all.insert(all.end(), args.begin(), args.end());
  return cementsph::testing::runProgram("timeout", all);
}

TEST(HostileViscosityOptions, AValidDropMatchesHagenPoiseuille) {
  const ProgramRun r = viscosity({"--viscosity-pa-s", "100", "--json"});
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const double mu = 100, L = 0.09, Q = 0.05e-6, D = 2.388e-3;
  const double expected = 128 * mu * L * Q / (M_PI * std::pow(D, 4));
  const auto at = r.out.find("\"pressure_drop_pa\":");
  ASSERT_NE(at, std::string::npos) << r.out;
  EXPECT_NEAR(std::stod(r.out.substr(at + 19)), expected, 1e-9 * expected);
}

TEST(HostileViscosityOptions, OverflowAndNonFiniteOptionsExitOneAndPrintNothing) {
  const std::vector<std::vector<std::string>> cases{
      {"--pressure-drop-mpa", "1e300", "--flow-rate-ml-per-s", "1e-300"},          // mu overflows
      {"--viscosity-pa-s", "1e300", "--flow-rate-ml-per-s", "1e300"},              // the drop overflows
      {"--viscosity-pa-s", "1e300", "--cannula-inner-diameter-mm", "1e-80"},       // D^4 underflows
      {"--consistency-pa-s-n", "1e300", "--flow-index", "3", "--flow-rate-ml-per-s", "1e100"},
      {"--pressure-drop-mpa", "1e300", "--flow-index", "0.1", "--flow-rate-ml-per-s", "1e-300"},
      {"--pressure-drop-mpa", "nan"},
      {"--pressure-drop-mpa", "inf"},
      {"--viscosity-pa-s", "nan", "--pressure-drop-mpa", "1"},
      {"--viscosity-pa-s", "-5"},
      {"--consistency-pa-s-n", "nan", "--flow-index", "1"},
  };
  for (const auto& args : cases) {
    for (const bool json : {false, true}) {
      std::vector<std::string> a = args;
      if (json) a.push_back("--json");
      std::ostringstream label;
      for (const auto& s : a) label << s << " ";
      const ProgramRun r = viscosity(a);
      EXPECT_EQ(r.exitCode, 1) << label.str() << "\n" << r.out << r.err;
      EXPECT_EQ(r.out, "") << label.str();
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << label.str() << "\n" << r.err;
      EXPECT_NE(r.err.find("--"), std::string::npos) << label.str() << ": the line must name an option: " << r.err;
      for (const char* word : {"inf ", "null"}) EXPECT_EQ(r.err.find(word), std::string::npos) << r.err;
    }
  }
}

} // namespace
