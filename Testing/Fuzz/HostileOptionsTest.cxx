// Issue 21: `cementsph viscosity` on options whose result overflows or is undefined. Each run must exit 1
// with one line on stderr naming the options, and print nothing (no `inf`, no `null` in --json); a valid
// run prints the drop Hagen-Poiseuille gives, computed here from the formula (dP = 128 mu L Q / (pi D^4)).
#include "ProgramRun.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
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

namespace {

namespace fs = std::filesystem;

ProgramRun program(const std::vector<std::string>& args) {
  std::vector<std::string> all{"-k", "5", "60", kProgram};
  all.insert(all.end(), args.begin(), args.end());
  return cementsph::testing::runProgram("timeout", all);
}

// Issue 21, second corpus (made by hand, /tmp/h5-corpus): option values that ran with a value nobody meant or
// hung. Each must exit 1 at once with one line naming the option (or the path), and leave no output folder.
TEST(HostileOptions, EmptySubnormalAndModeClashingValuesAreRefusedNamingTheOption) {
  const fs::path scratch = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "hostile-options";
  fs::remove_all(scratch);
  fs::create_directories(scratch);
  const std::string volume = (fs::path(CEMENTSPH_TEST_DATA_DIR) / "foam-phantom" / "pre.nrrd").string();
  const std::string out = (scratch / "out").string();
  const std::vector<std::string> drr{"drr", "--volume", volume, "--out", out, "--detector-pixels", "16,16"};
  auto with = [](std::vector<std::string> base, const std::vector<std::string>& more) {
    base.insert(base.end(), more.begin(), more.end());
    return base;
  };
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      // "" was read as 0 (a 0 mm shell, a gantry angle of 0) or as an empty path (inject wrote into the
      // current folder).
      {with(drr, {"--gantry-angle-deg", ""}), "--gantry-angle-deg"},
      {{"drr", "--volume", volume, "--out", ""}, "--out"},
      {{"phantom", "--out", out, "--shell-mm", ""}, "--shell-mm"},
      // 1e-320 is subnormal: it turned into infinities that blamed other options.
      {with(drr, {"--sid-mm", "1e-320"}), "--sid-mm"},
      {{"phantom", "--out", out, "--cell-size-mm", "1e-320"}, "--cell-size-mm"},
      // Past the ceiling of the option's unit (1e6 mm): 1e308 reached ITK, whose message was the error line.
      {{"compare", "--pre", volume, "--post", volume, "--injection-point-mm", "1,1,1", "--out", out,
        "--closing-radius-mm", "1e308"},
       "--closing-radius-mm"},
      {{"compare", "--pre", volume, "--post", volume, "--injection-point-mm", "1,1,1e308", "--out", out},
       "--injection-point-mm"},
      {with(drr, {"--gantry-angle-deg", "1e300"}), "--gantry-angle-deg"},
      // A cone-beam source 1 mm from the isocentre lies inside the 30 mm block: it drew a DRR.
      {with(drr, {"--sad-mm", "1"}), "--sad-mm"},
      // The geometry's complaint names the option that set it.
      {with(drr, {"--sid-mm", "5"}), "--sid-mm"},
      {with(drr, {"--sad-mm", "-0"}), "--sad-mm"},
      // 2^31 detector pixels ran for minutes.
      {with(drr, {"--detector-pixels", "46341,46341"}), "--detector-pixels"},
      // 0 means "not given" in viscosity's modes, and the gauge overrode a given diameter.
      {{"viscosity", "--pressure-drop-mpa", "1", "--flow-index", "0"}, "--flow-index"},
      {{"viscosity", "--pressure-drop-mpa", "1", "--cannula-gauge", "10G", "--cannula-inner-diameter-mm", "2"},
       "--cannula-gauge"},
      // Each value of a sweep is a full injection.
      {{"study", "--ct", volume, "--scene", "x.json", "--out", out, "--viscosities-pa-s",
        [] {
          std::string many;
          for (int i = 0; i < 101; ++i) many += (i ? "," : "") + std::to_string(10 + i);
          return many;
        }()},
       "--viscosities-pa-s"},
  };
  for (const auto& [args, option] : cases) {
    std::ostringstream label;
    for (const auto& s : args) label << "'" << s << "' ";
    const ProgramRun r = program(args);
    EXPECT_EQ(r.exitCode, 1) << label.str() << "\n" << r.out << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << label.str() << "\n" << r.err;
    EXPECT_NE(r.err.find(option), std::string::npos) << label.str() << ": the line must name " << option << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << label.str() << " left " << out;
    fs::remove_all(out);
  }
  // The limits themselves still run: 0 gantry angle typed as such, a thin detector.
  const ProgramRun ok = program(with(drr, {"--gantry-angle-deg", "0", "--quiet"}));
  EXPECT_EQ(ok.exitCode, 0) << ok.err;
  EXPECT_TRUE(fs::exists(fs::path(out) / "drr.nrrd"));
}

// A FIFO given as the CT or the scene: opening it waits for a writer forever (the corpus's runs hung until
// killed). Refused before it is opened, naming the path, well inside the 60 s timeout.
TEST(HostileOptions, AFifoGivenAsAnInputIsRefusedAtOnce) {
  const fs::path scratch = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "hostile-fifo";
  fs::remove_all(scratch);
  fs::create_directories(scratch);
  const std::string fifo = (scratch / "ct.nrrd").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string volume = (fs::path(CEMENTSPH_TEST_DATA_DIR) / "foam-phantom" / "pre.nrrd").string();
  const std::string out = (scratch / "out").string();
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"drr", "--volume", fifo, "--out", out},
           {"inject", "--ct", volume, "--scene", fifo, "--out", out},
           {"inject", "--ct", fifo, "--scene", fifo, "--out", out}}) {
    const ProgramRun r = program(args);
    EXPECT_EQ(r.exitCode, 1) << args[0] << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(fifo + ": not a regular file"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

} // namespace

namespace {

// darcy with too few steps to converge: a failed run (status 2) whose reason is one line even under --quiet,
// naming the option to raise (it returned 2 with nothing on stderr). The CSV keeps the rows, marked converged 0.
TEST(HostileOptions, ADarcyRunThatDoesNotConvergeSaysSoUnderQuiet) {
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "hostile-darcy";
  fs::remove_all(out);
  const ProgramRun r = program({"darcy", "--porosities", "0.5", "--spacings-mm", "1", "--viscosities-pa-s", "10",
                                "--lattice", "5", "--max-steps-per-force", "10", "--no-plot", "--quiet", "--out",
                                out.string()});
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("--max-steps-per-force 10"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
}

} // namespace
