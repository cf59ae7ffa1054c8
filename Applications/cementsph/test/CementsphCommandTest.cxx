// The cementsph program as a user meets it: help, bad input (one clear line, non-zero exit, no output
// files), and a small real `darcy` run whose CSV has the documented columns.
#include "ProgramRun.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

struct Result {
  int status;
  std::string output; // stdout and stderr together
};

Result run(const std::string& args) {
  const cementsph::testing::ProgramRun r = cementsph::testing::runProgram(CEMENTSPH_EXECUTABLE, args);
  return {r.exitCode, r.out + r.err};
}

fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / name;
  fs::remove_all(p);
  return p;
}

} // namespace

TEST(CementsphCommand, HelpListsSubcommands) {
  const Result r = run("--help");
  EXPECT_EQ(r.status, 0);
  // Every subcommand the README documents, each on its own line of the list (name, then its summary): a command
  // that stopped registering itself fails here (checked once by removing viscosity's registration).
  for (const char* name : {"compare", "darcy", "demo", "drr", "inject", "phantom", "plan", "register", "study",
                           "viscosity", "xray"})
    EXPECT_NE(r.output.find(std::string("\n  ") + name + " "), std::string::npos) << name << ": " << r.output;
  const Result d = run("darcy --help");
  EXPECT_EQ(d.status, 0);
  EXPECT_NE(d.output.find("--spacings-mm"), std::string::npos) << d.output;
}

TEST(CementsphCommand, BadPorosityIsOneClearLineAndNoOutput) {
  const fs::path out = scratch("bad-porosity");
  const Result r = run("darcy --porosities 0 --out " + out.string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("--porosities"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(fs::exists(out / "permeability.csv"));
}

TEST(CementsphCommand, UnknownPresetIsAClearError) {
  const fs::path out = scratch("bad-preset");
  const Result r = run("darcy --preset nonsense --out " + out.string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("unknown preset 'nonsense'"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "permeability.csv"));
}

TEST(CementsphCommand, SmallDarcyRunWritesCsvAndPlot) {
  const fs::path out = scratch("darcy-small");
  const Result r = run("darcy --lattice 6 --porosities 0.9 --spacings-mm 1 --viscosities-pa-s 10 --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream csv(out / "permeability.csv");
  ASSERT_TRUE(csv) << r.output;
  std::string header, row;
  std::getline(csv, header);
  std::getline(csv, row);
  for (const char* column : {"porosity", "spacing_mm", "viscosity_pa_s", "slope", "r2", "permeability_m2",
                             "dimensionless_permeability", "steps", "wall_s"})
    EXPECT_NE(header.find(column), std::string::npos) << column;
  EXPECT_FALSE(row.empty());
  // porosity 1 - round(0.1 * 216) / 216 = 0.8981...
  EXPECT_EQ(row.rfind("0.89814815,1,10,", 0), 0u) << row;
  std::ifstream png(out / "permeability.png", std::ios::binary);
  ASSERT_TRUE(png);
  char magic[8] = {};
  png.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator()), 2); // no temporaries
}

// darcy options the simulation would refuse later with a line naming no option (issue 21, second corpus): each is
// status 1, one line naming the option, and no output folder. Oracle for --lattice: the periodic box n d must be
// wider than twice the neighbour-list radius 2h (1 + skin/2), h = (h/d) d, skin 0.2 (ModelParameters), so
// n > 4 (h/d) 1.1: at the default preset's h/d 1 the least n is 5 (4.4), at --h-over-d 2 it is 9 (8.8).
TEST(CementsphCommand, DarcyOptionsTheSimulationWouldRefuseAreNamed) {
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::vector<std::string>>>{
           {"--lattice 4", {"--lattice: 4 particles", "--lattice 5 or more"}},
           {"--lattice 8 --h-over-d 2", {"--lattice: 8 particles", "at h/d 2", "--lattice 9 or more"}},
           {"--lattice 6 --integrator rk4", {"--integrator: unknown integrator 'rk4'"}},
           {"--lattice 6 --viscosity-model x", {"--viscosity-model: unknown viscosity model 'x'"}},
           // The permeability is a fitted slope: one force gives none.
           {"--lattice 6 --body-forces-m-per-s2 5", {"--body-forces-m-per-s2: give at least two"}}}) {
    const fs::path out = scratch("darcy-named-option");
    const Result r = run("darcy --porosities 0.5 --spacings-mm 1 --viscosities-pa-s 10 --max-steps-per-force 2000 "
                         "--no-plot --quiet --out " + out.string() + " " + args);
    EXPECT_EQ(r.status, 1) << args << "\n" << r.output;
    for (const std::string& part : expected) EXPECT_NE(r.output.find(part), std::string::npos) << args << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(out)) << args;
  }
}

// More cement than the CT can hold: the phantom is a 12 mm block with a 1 mm air margin, (14 mm)^3 = 2.744 ml in
// all, so 16 ml cannot fit whatever its pores. The line names the option (the pore-space check knows only the
// volume), status 1, no output folder.
TEST(CementsphCommand, MoreCementThanThePoresHoldNamesVolumeMl) {
  const fs::path out = scratch("phantom-too-much-cement");
  const Result r = run("phantom --size-mm 12 --cell-size-mm 3 --shell-mm 0 --air-margin-mm 1 --quiet --volume-ml 16 "
                       "--out " + out.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("16 ml to inject"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--volume-ml"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

// Conventions every subcommand shares (issue "A toolkit people build on", item 5).
TEST(CementsphCommand, AnUnknownSubcommandIsNamedWithTheList) {
  const Result r = run("injekt --ct x.nrrd");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("'injekt' is not a subcommand"), std::string::npos) << r.output;
  // The README's subcommands, listed in the line.
  for (const char* name : {"compare", "darcy", "demo", "drr", "inject", "phantom", "plan", "register", "study",
                           "viscosity", "xray"})
    EXPECT_NE(r.output.find(name), std::string::npos) << name << ": " << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}

TEST(CementsphCommand, QuietPrintsNothingButErrorsOnEverySubcommand) {
  // Hagen-Poiseuille through the default 11G cannula: a run that prints its figures, then the same quiet.
  const Result loud = run("viscosity --viscosity-pa-s 100");
  ASSERT_EQ(loud.status, 0) << loud.output;
  EXPECT_FALSE(loud.output.empty());
  const Result quiet = run("viscosity --viscosity-pa-s 100 --quiet");
  EXPECT_EQ(quiet.status, 0) << quiet.output;
  EXPECT_EQ(quiet.output, "");
  // An error still reaches stderr under --quiet.
  const Result bad = run("viscosity --viscosity-pa-s -1 --quiet");
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.output.find("--viscosity-pa-s"), std::string::npos) << bad.output;
  // Every subcommand takes --quiet (its help lists it).
  for (const char* name : {"compare", "darcy", "demo", "inject", "phantom", "plan", "register", "study",
                           "viscosity", "xray"}) {
    const Result help = run(std::string(name) + " --help");
    EXPECT_NE(help.output.find("--quiet"), std::string::npos) << name;
  }
}

TEST(CementsphCommand, AMisspeltRenderBackendIsRefusedBeforeAnyWork) {
  const fs::path out = scratch("bad-backend");
  setenv("CEMENTSPH_RENDER_BACKEND", "osmeas", 1);
  const Result r = run("darcy --lattice 6 --porosities 0.8 --spacings-mm 1 --viscosities-pa-s 10 --out " + out.string());
  unsetenv("CEMENTSPH_RENDER_BACKEND");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("CEMENTSPH_RENDER_BACKEND is 'osmeas'"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(fs::exists(out / "permeability.csv"));
}

// A floating-point option takes finite numbers only, on every subcommand (CLI11's ranges let NaN through).
TEST(CementsphCommand, NaNAndInfiniteNumbersAreRefusedOnEveryOption) {
  for (const auto& [args, option] : std::vector<std::pair<std::string, std::string>>{
           {"compare --pre a.nrrd --post b.nrrd --injection-point-mm 1,2,3 --injection-search-radius-mm nan --out x",
            "--injection-search-radius-mm"},
           {"compare --pre a.nrrd --post b.nrrd --injection-point-mm 1,2,3 --closing-radius-mm inf --out x",
            "--closing-radius-mm"},
           {"inject --ct a.nrrd --scene s.json --tip-mm 1,nan,3 --out x", "--tip-mm"},
           {"viscosity --viscosity-pa-s 1e999", "--viscosity-pa-s"},
           {"plan --ct a.nrrd --scene s.json --out x --entry-mm 0,0,0 --direction 0,0,1 --target-mm 0,0,5 "
            "--target-radius-mm -inf",
            "--target-radius-mm"}}) {
    const Result r = run(args);
    EXPECT_EQ(r.status, 1) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(option + ": must be a finite number"), std::string::npos) << args << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  }
}

// The particle snapshots are written on a second thread (InjectionOutputs.h): a snapshot the file system refuses
// must still fail the run whole. Under a 4096-byte file size limit (prlimit; cementsph ignores SIGXFSZ, so the
// write meets EFBIG rather than a signal) no 0.5 ml snapshot series fits: the last snapshot alone holds the float
// x, y, z of every wet voxel, 0.5 ml / (0.5 mm)^3 = 4000 voxels x 12 bytes = 48 kB before compression, and LZ4
// cannot pack grid coordinates 12-fold. Expected: exit 2, one line naming a particles_NNNN.vtp and the limit,
// no signal, and none of the run's files left (no metrics.json, no snapshot).
TEST(CementsphCommand, ASnapshotTheDiskRefusesFailsTheRunWhole) {
  const cementsph::testing::ProgramRun probe = cementsph::testing::runProgram("prlimit", "--version");
  if (probe.exitCode != 0) GTEST_SKIP() << "prlimit (util-linux) is not installed";
  const fs::path out = scratch("snapshot-limit");
  const std::string data = CEMENTSPH_TEST_DATA_DIR;
  const cementsph::testing::ProgramRun r = cementsph::testing::runProgram(
      "prlimit", {"--fsize=4096", CEMENTSPH_EXECUTABLE, "inject", "--ct", data + "/foam-phantom/pre.nrrd", "--scene",
                  data + "/scenes/paper.json", "--tip-mm", "22.325,21.855,21.75", "--volume-ml", "0.5", "--no-pictures",
                  "--quiet", "--threads", "1", "--out", out.string()});
  EXPECT_EQ(r.exitCode, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("particles_"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("file size limit"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(out / "metrics.json"));
  bool snapshotLeft = false;
  if (fs::exists(out))
    for (const auto& entry : fs::directory_iterator(out))
      snapshotLeft = snapshotLeft || entry.path().filename().string().rfind("particles_", 0) == 0;
  EXPECT_FALSE(snapshotLeft);
}
