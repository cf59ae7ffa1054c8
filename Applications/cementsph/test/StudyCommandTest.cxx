// `cementsph study` as a user meets it, on the bundled foam phantom with a tiny volume: the files, one row
// per run in the CSV and the Markdown, the progress lines, no temporaries; and bad options: one line, a
// non-zero exit, no output folder.
#include "PhantomTip.h"
#include "ProgramRun.h"

#include <gtest/gtest.h>

#include <regex>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

const fs::path kData = CEMENTSPH_TEST_DATA_DIR;

struct Result {
  int status;
  std::string out, err;
};

Result run(const std::vector<std::string>& args) {
  setenv("OMP_NUM_THREADS", "1", 1); // the child inherits it: one thread on shared cores
  const cementsph::testing::ProgramRun r = cementsph::testing::runProgram(CEMENTSPH_EXECUTABLE, args);
  return {r.exitCode, r.out, r.err};
}

fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

std::string phantomTip() { return cementsph::testing::foamPhantomTipArgument(kData); }

// The study command on the phantom with the given extra arguments.
std::vector<std::string> studyArgs(const fs::path& out, std::vector<std::string> extra, const std::string& tip = "",
                                   const std::string& scene = "") {
  std::vector<std::string> args{"study",         "--ct",       (kData / "foam-phantom" / "pre.nrrd").string(),
                                "--scene",       scene.empty() ? (kData / "scenes" / "paper-1ml.json").string() : scene,
                                "--tip-mm",      tip.empty() ? phantomTip() : tip,
                                "--volume-ml",   "0.03",
                                "--out",         out.string()};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::size_t count(const std::vector<std::string>& all, const std::string& prefix) {
  return static_cast<std::size_t>(
      std::count_if(all.begin(), all.end(), [&](const std::string& l) { return l.rfind(prefix, 0) == 0; }));
}

} // namespace

TEST(StudyCommand, WritesOneRowPerRunAndLeavesNoTemporaries) {
  const fs::path dir = scratch("study-cli");
  const fs::path out = dir / "out";
  const Result r = run(studyArgs(out, {"--radii-mm", "1.0,0.75", "--integrators", "overdamped,central-difference",
                                       "--viscosities-pa-s", "100,400", "--no-pictures"}));
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("study done: 6 runs"), std::string::npos) << r.out;
  // One progress line per run.
  const auto progress = lines(r.err);
  EXPECT_EQ(count(progress, "study size "), 4u) << r.err;
  EXPECT_EQ(count(progress, "study viscosity "), 2u) << r.err;
  EXPECT_NE(r.err.find("study size 1/4: central-difference r 0.75 mm (reference)"), std::string::npos) << r.err;

  const auto csv = lines(slurp(out / "study.csv"));
  ASSERT_EQ(csv.size(), 5u);
  EXPECT_EQ(csv[0].rfind("run,integrator,particle_radius_mm,reference,status,wall_time_s,", 0), 0u) << csv[0];
  EXPECT_EQ(csv[1].rfind("1,central-difference,0.75,1,ok,", 0), 0u) << csv[1];
  EXPECT_EQ(csv[4].rfind("4,central-difference,1,0,ok,", 0), 0u) << csv[4];
  const auto sweep = lines(slurp(out / "spreading_vs_viscosity.csv"));
  ASSERT_EQ(sweep.size(), 3u);
  EXPECT_EQ(sweep[2].rfind("400,0.57,overdamped,ok,", 0), 0u) << sweep[2];

  const auto md = lines(slurp(out / "study.md"));
  EXPECT_EQ(count(md, "| overdamped | "), 2u) << slurp(out / "study.md");
  EXPECT_EQ(count(md, "| central-difference"), 2u);
  EXPECT_EQ(count(md, "| central-difference (reference) | 0.75 |"), 1u);
  EXPECT_EQ(count(md, "| 100 | 0.57 | overdamped | "), 1u); // the sweep, at the scene's radius
  EXPECT_EQ(count(md, "| 400 | 0.57 | overdamped | "), 1u);

  std::ifstream j(out / "study.json");
  const nlohmann::json study = nlohmann::json::parse(j);
  EXPECT_EQ(study["size_runs_done"].get<int>(), 4);
  EXPECT_EQ(study["viscosity_runs_done"].get<int>(), 2);
  EXPECT_GT(study["runs_wall_time_s"].get<double>(), 0.0);
  EXPECT_EQ(study["radii_mm"], nlohmann::json::parse("[1.0, 0.75]"));

  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(out)) files.push_back(e.path().filename().string());
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files, (std::vector<std::string>{"spreading_vs_viscosity.csv", "study.csv", "study.json", "study.md"}));
  for (const auto& f : files) {
    const std::string text = slurp(out / f);
    // "nan" as a value, not inside a word ("provenance").
    EXPECT_FALSE(std::regex_search(text, std::regex("(^|[^a-z])nan([^a-z]|$)", std::regex::icase))) << f;
    EXPECT_EQ(text.find("inf,"), std::string::npos) << f;
  }
}

TEST(StudyCommand, KeepRunsKeepsEachRunsInjectOutputs) {
  const fs::path out = scratch("study-keep") / "out";
  const Result r = run(studyArgs(out, {"--radii-mm", "1.0", "--integrators", "overdamped", "--keep-runs",
                                       "--no-pictures"}));
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  EXPECT_TRUE(fs::exists(out / "runs" / "overdamped_r1.00mm" / "simulated_ct.nrrd"));
  EXPECT_TRUE(fs::exists(out / "runs" / "overdamped_r1.00mm" / "metrics.json"));
}

TEST(StudyCommand, BadOptionsAreOneLineAndNoOutput) {
  const fs::path dir = scratch("study-bad");
  const fs::path out = dir / "out";
  std::ofstream(dir / "rising.json") << R"({"scene_preset": "paper", "viscosity_rate_pa_per_s": 2})";
  struct Case {
    std::vector<std::string> extra;
    std::string says;
    std::string tip;
    std::string scene;
  };
  const std::vector<Case> cases{
      {{"--radii-mm", "0.5,-1"}, "--radii-mm: -1 is not a positive number", "", ""},
      {{"--radii-mm", "0.5,0.5"}, "--radii-mm: 0.5 is given twice", "", ""},
      {{"--integrators", "leapfrog"}, "--integrators: unknown integrator 'leapfrog'", "", ""},
      {{"--viscosities-pa-s", "100,0"}, "--viscosities-pa-s: 0 is not a positive number", "", ""},
      {{"--no-size-study"}, "nothing to run", "", ""},
      {{"--no-registration"}, "--no-registration needs --reference-ct", "", ""},
      {{"--reference-ct", (dir / "missing.nrrd").string()}, "missing.nrrd", "", ""},
      {{"--threads", "-2"}, "--threads: -2 is negative", "", ""},
      {{"--set", "particle_radius_mm=0"}, "particle_radius_mm", "", ""},
      {{"--viscosities-pa-s", "100"}, "viscosity_rate_pa_per_s", "", (dir / "rising.json").string()},
      // Found only by the first run (the porous solid): still nothing written.
      {{"--radii-mm", "0.75"}, "lies in solid", "9,22.09,22", ""}, // a strut of the phantom
      {{"--radii-mm", "0.75"}, "lies outside the CT", "500,22,22", ""},
  };
  for (const Case& c : cases) {
    const Result r = run(studyArgs(out, c.extra, c.tip, c.scene));
    const std::string all = r.out + r.err;
    EXPECT_EQ(r.status, 1) << all;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_EQ(std::count(all.begin(), all.end(), '\n'), 1) << all;
    EXPECT_EQ(r.err.rfind("cementsph study: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << "'" << r.err << "' lacks '" << c.says << "'";
    EXPECT_FALSE(fs::exists(out)) << c.says;
  }
  // An output path that is a file.
  std::ofstream(dir / "file") << "x";
  const Result r = run(studyArgs(dir / "file", {}));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("exists and is not a folder"), std::string::npos) << r.err;
}

// Issue 22 item 2: a study shows it is working before its first run is done (an MPI study printed nothing for
// 7 minutes): a line as each run starts, before that run's result line, and nothing with --quiet.
TEST(StudyCommand, EachRunIsAnnouncedBeforeItsResult) {
  const fs::path out = scratch("study-progress") / "out";
  const Result r = run(studyArgs(out, {"--radii-mm", "1.0,0.75", "--integrators", "overdamped",
                                       "--viscosities-pa-s", "100", "--no-pictures"}));
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  const auto progress = lines(r.err);
  const std::vector<std::string> runs{"size 1/2: overdamped r 0.75 mm (reference)", "size 2/2: overdamped r 1.00 mm",
                                      "viscosity 1/1: overdamped r 0.57 mm, 100 Pa.s"};
  std::size_t at = 0; // the lines in this order: start of run k, its result, start of run k + 1, ...
  for (const std::string& run : runs) {
    const auto start = std::find(progress.begin() + long(at), progress.end(), "study starting " + run);
    ASSERT_NE(start, progress.end()) << "no start line for " << run << " after line " << at << ":\n" << r.err;
    const auto result = std::find_if(start, progress.end(),
                                     [&](const std::string& l) { return l.rfind("study " + run + ": ", 0) == 0; });
    ASSERT_NE(result, progress.end()) << "no result line for " << run << " after its start:\n" << r.err;
    at = std::size_t(result - progress.begin()) + 1;
  }
  EXPECT_EQ(count(progress, "study starting "), 3u) << r.err;

  const Result quiet = run(studyArgs(scratch("study-progress-quiet") / "out",
                                     {"--radii-mm", "1.0", "--integrators", "overdamped", "--no-pictures", "--quiet"}));
  ASSERT_EQ(quiet.status, 0) << quiet.err;
  EXPECT_EQ(quiet.out + quiet.err, "");
}
