// Hostile command lines (issue 21, the corpus's leftovers of session 6), through the real program: each bad
// input gives exit status 1, stderr of exactly one line that names the input at fault (the option, the scene key
// or the file) and the problem, and no output folder. The oracle of each case is the input itself: which option
// the test gave, and the folder it named, which must not exist afterwards.
#include "PhantomTip.h"
#include "ProgramRun.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

using cementsph::testing::ProgramRun;

const fs::path kData = fs::path(CEMENTSPH_TEST_DATA_DIR);
const std::string kCt = (kData / "foam-phantom" / "pre.nrrd").string();

// A scratch folder of this test process (ctest may run suites in parallel).
fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / ("hostile-command-line-" + std::to_string(::getpid())) / name;
  fs::remove_all(p);
  fs::create_directories(p.parent_path());
  return p;
}

ProgramRun run(const std::vector<std::string>& args) { return cementsph::testing::runProgram(CEMENTSPH_EXECUTABLE, args); }

std::string writeText(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

// The scene of these runs: the foam phantom's tip, a small volume.
std::string sceneFile(const fs::path& dir) {
  const std::string tip = cementsph::testing::foamPhantomTipArgument(kData);
  return writeText(dir / "scene.json", "{\"tip_mm\": [" + tip + "], \"volume_ml\": 0.05}");
}

// Exit status 1, one line on stderr (nothing on stdout but what the command printed before: nothing here) that
// holds every one of `named`, and `out` not created.
void expectRefused(const ProgramRun& r, const std::vector<std::string>& named, const fs::path& out) {
  EXPECT_EQ(r.exitCode, 1) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_LT(r.err.size(), 500u) << r.err;
  for (const std::string& n : named) EXPECT_NE(r.err.find(n), std::string::npos) << "'" << n << "' not in: " << r.err;
  EXPECT_FALSE(fs::exists(out)) << out;
}

} // namespace

// CLI11 read an integer option's '010' as octal 8 and '0x10' as 16, and strtod read a floating-point option's
// '0x10' and '0x1p3' (16 and 8): refused as not decimal, naming the option.
TEST(HostileCommandLine, NumbersThatAreNotDecimalAreRefused) {
  const fs::path dir = scratch("decimal"), out = dir / "out";
  const std::string scene = sceneFile(dir);
  expectRefused(run({"inject", "--ct", kCt, "--scene", scene, "--out", out.string(), "--volume-ml", "0x10"}),
                {"--volume-ml", "'0x10'", "decimal"}, out);
  expectRefused(run({"phantom", "--out", out.string(), "--size-mm", "0x1p3"}), {"--size-mm", "decimal"}, out);
  expectRefused(run({"plan", "--ct", kCt, "--scene", scene, "--out", out.string(), "--entry-mm", "1,1,1", "--target-mm",
                     "2,2,2", "--starts", "010"}),
                {"--starts", "'010'", "octal"}, out);
  expectRefused(run({"darcy", "--out", out.string(), "--lattice", "0b101"}), {"--lattice", "decimal"}, out);
  // A whole number with a leading zero is refused for an integer option only: '010' mm is 10 mm.
  const ProgramRun ok = run({"viscosity", "--pressure-drop-mpa", "01.5"});
  EXPECT_EQ(ok.exitCode, 0) << ok.err;
}

// CLI11's "Could not convert: --starts = 1_0" in words.
TEST(HostileCommandLine, ANumberThatDoesNotConvertNamesTheOptionInWords) {
  const fs::path dir = scratch("convert"), out = dir / "out";
  const ProgramRun r = run({"plan", "--ct", kCt, "--scene", sceneFile(dir), "--out", out.string(), "--entry-mm", "1,1,1",
                            "--target-mm", "2,2,2", "--starts", "1_0"});
  expectRefused(r, {"--starts", "'1_0'", "is not a number"}, out);
  EXPECT_EQ(r.err.find("Could not convert"), std::string::npos) << r.err;
}

// --out is a folder for every subcommand: a file, a symbolic link to nothing, or a path under a file is refused
// before any work, naming --out; the file is left as it was.
TEST(HostileCommandLine, AnOutputFolderThatIsAFileOrADanglingLinkIsRefused) {
  const fs::path dir = scratch("out-folder");
  const std::string file = writeText(dir / "a-file", "keep me");
  const fs::path dangling = dir / "dangling";
  fs::create_symlink(dir / "nowhere", dangling);
  const std::string scene = sceneFile(dir);
  for (const auto& [out, problem] : std::vector<std::pair<std::string, std::string>>{
           {file, "exists and is not a folder"}, {dangling.string(), "symbolic link to nothing"}, {file + "/sub", "lies under"}}) {
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"inject", "--ct", kCt, "--scene", scene, "--out", out},
          std::vector<std::string>{"plan", "--ct", kCt, "--scene", scene, "--out", out, "--entry-mm", "1,1,1", "--target-mm", "2,2,2"},
          std::vector<std::string>{"phantom", "--out", out}, std::vector<std::string>{"darcy", "--out", out}}) {
      const ProgramRun r = run(args);
      EXPECT_EQ(r.exitCode, 1) << args[0] << " " << out << ": " << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
      EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
      EXPECT_NE(r.err.find(problem), std::string::npos) << r.err;
    }
  }
  std::ifstream in(file);
  std::string kept;
  std::getline(in, kept);
  EXPECT_EQ(kept, "keep me");
  EXPECT_FALSE(fs::exists(dir / "nowhere"));
}

// A path of 4000 characters is shown by its two ends: the line stays under 500 characters and names the option.
TEST(HostileCommandLine, AVeryLongPathIsShortenedInTheErrorLine) {
  const fs::path dir = scratch("long-path"), out = dir / "out";
  const std::string longCt = (dir / std::string(4000, 'x')).string() + "/ct.nrrd";
  const ProgramRun r = run({"inject", "--ct", longCt, "--scene", sceneFile(dir), "--out", out.string()});
  expectRefused(r, {"ct.nrrd", "..."}, out);
  // A unicode path that does not exist: named as given (UTF-8 passes through).
  const std::string unicodeCt = (dir / "wirbelkörper-椎骨.nrrd").string();
  expectRefused(run({"inject", "--ct", unicodeCt, "--scene", sceneFile(dir), "--out", out.string()}),
                {"wirbelkörper-椎骨.nrrd"}, out);
}

// An option that takes one value, given twice with different values: refused, not the last silently kept.
TEST(HostileCommandLine, AnOptionGivenTwiceIsRefused) {
  const fs::path dir = scratch("twice"), out = dir / "out";
  const ProgramRun r = run({"inject", "--ct", kCt, "--scene", sceneFile(dir), "--out", out.string(), "--volume-ml", "0.05",
                            "--volume-ml", "0.1"});
  expectRefused(r, {"--volume-ml"}, out);
}

// xray's frame times name --sequence-times-s (the frame list's own check named --sequence, the volumes).
TEST(HostileCommandLine, DecreasingSequenceTimesNameTheirOption) {
  const fs::path dir = scratch("times"), out = dir / "out";
  expectRefused(run({"xray", "--sequence", kCt + "," + kCt, "--sequence-times-s", "5,1", "--out", out.string()}),
                {"--sequence-times-s", "frame times must increase", "1 s after 5 s"}, out);
}

// study --radii-mm: a radius whose particle does not fit the cannula names --radii-mm and the limit (the default
// cannula_inner_diameter_mm 2.388: radii up to 1.194 mm), not the scene's cannula key alone.
TEST(HostileCommandLine, AStudyRadiusTooLargeForTheCannulaNamesRadii) {
  const fs::path dir = scratch("radii"), out = dir / "out";
  expectRefused(run({"study", "--ct", kCt, "--scene", sceneFile(dir), "--out", out.string(), "--radii-mm", "0.5,16"}),
                {"--radii-mm 16", "cannula", "1.194"}, out);
}

// plan: too few evaluations for the starts names both options and the count needed: 16 starts of 6 = 96.
TEST(HostileCommandLine, TooFewEvaluationsForTheStartsNameBothOptions) {
  const fs::path dir = scratch("starts"), out = dir / "out";
  expectRefused(run({"plan", "--ct", kCt, "--scene", sceneFile(dir), "--out", out.string(), "--entry-mm", "19,22,5",
                     "--target-mm", "19,22,20", "--max-evaluations", "6", "--starts", "16"}),
                {"--max-evaluations 6", "--starts 16", "96"}, out);
}

// inject: a tip outside the CT names --tip-mm when that gave it, else the scene file and its key tip_mm; the
// foam phantom's CT spans 0 .. 44 mm, so 1e5 mm is outside.
TEST(HostileCommandLine, ATipOutsideTheCTNamesWhereItCameFrom) {
  const fs::path dir = scratch("tip"), out = dir / "out";
  const std::string scene = sceneFile(dir);
  expectRefused(run({"inject", "--ct", kCt, "--scene", scene, "--out", out.string(), "--tip-mm", "100000,0,0"}),
                {"--tip-mm", "outside the CT"}, out);
  const std::string far = writeText(dir / "far.json", R"({"tip_mm": [1e9, 1e9, 1e9], "volume_ml": 0.05})");
  expectRefused(run({"inject", "--ct", kCt, "--scene", far, "--out", out.string()}), {far, "'tip_mm'", "outside the CT"},
                out);
}

// inject --labels on another grid names --labels (it was blamed on the scene key labels_path).
TEST(HostileCommandLine, LabelsOnAnotherGridNameTheOption) {
  const fs::path dir = scratch("labels"), out = dir / "out";
  const std::string labels =
      writeText(dir / "labels.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nspacings: 1 1 1\nencoding: raw\n\n" +
                                         std::string(8, '\1'));
  expectRefused(run({"inject", "--ct", kCt, "--scene", sceneFile(dir), "--out", out.string(), "--labels", labels}),
                {"--labels " + labels, "not on the CT's grid"}, out);
}

// --set without a key names --set.
TEST(HostileCommandLine, ASetWithoutAKeyNamesSet) {
  const fs::path dir = scratch("set"), out = dir / "out";
  expectRefused(run({"inject", "--ct", kCt, "--scene", sceneFile(dir), "--out", out.string(), "--set", "=5"}),
                {"--set '=5'", "key=value"}, out);
}

// viscosity --cannula-gauge 99G names the option and lists the gauges there are.
TEST(HostileCommandLine, AnUnknownGaugeNamesTheOption) {
  const ProgramRun r = run({"viscosity", "--pressure-drop-mpa", "1", "--cannula-gauge", "99G"});
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("--cannula-gauge"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("11G"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// phantom --cell-size-mm below a voxel (0.5 mm: 0.001 mm asked for 1.7e12 seeds, "out of memory") or above the
// block's smallest edge (12 mm: "the block has no sub-samples") names the option and the limit.
TEST(HostileCommandLine, AFoamCellOutsideTheGridAndBlockNamesCellSize) {
  const fs::path out = scratch("cell") / "out";
  expectRefused(run({"phantom", "--out", out.string(), "--size-mm", "12", "--cell-size-mm", "0.001"}),
                {"--cell-size-mm 0.001", "voxel", "0.5 mm"}, out);
  expectRefused(run({"phantom", "--out", out.string(), "--size-mm", "12", "--cell-size-mm", "16"}),
                {"--cell-size-mm 16", "12 mm"}, out);
}

// --threads above the cores is capped, and says so in one line on stderr (not silently); --quiet silences it.
TEST(HostileCommandLine, ThreadsAboveTheCoresAreCappedWithANote) {
  const fs::path out = scratch("threads") / "out";
  const std::vector<std::string> phantom{"phantom",      "--out", out.string(), "--size-mm", "12", "--cell-size-mm", "3",
                                         "--shell-mm",   "0",     "--air-margin-mm", "1", "--volume-ml", "0.1",
                                         "--threads",    "99999"};
  const ProgramRun r = run(phantom);
  EXPECT_EQ(r.exitCode, 0) << r.err;
  // The note first (before the run's own progress lines), once.
  EXPECT_EQ(r.err.rfind("cementsph phantom: note: --threads 99999 is more than this machine's ", 0), 0u) << r.err;
  EXPECT_EQ(r.err.find("note:", 30), std::string::npos) << r.err;
  std::vector<std::string> quiet = phantom;
  quiet.push_back("--quiet");
  const ProgramRun q = run(quiet);
  EXPECT_EQ(q.exitCode, 0) << q.err;
  EXPECT_EQ(q.err.find("note:"), std::string::npos) << q.err;
}

// An option of one value given twice, and a vector option given the wrong count, in words (CLI11 said "At Most 1
// required but received 2"); --labels naming a folder that is no label map names --labels.
TEST(HostileCommandLine, ValueCountsAndLabelFoldersAreInWords) {
  const fs::path dir = scratch("counts"), out = dir / "out";
  const std::string scene = sceneFile(dir);
  const ProgramRun twice = run({"inject", "--ct", kCt, "--scene", scene, "--out", out.string(), "--volume-ml", "0.05",
                                "--volume-ml", "0.1"});
  expectRefused(twice, {"--volume-ml: takes one value but was given 2", "give it once"}, out);
  EXPECT_EQ(twice.err.find("At Most"), std::string::npos) << twice.err;
  expectRefused(run({"inject", "--ct", kCt, "--scene", scene, "--out", out.string(), "--tip-mm", "1,2,3,4"}),
                {"--tip-mm: takes 3 values but was given 4: give 3"}, out);
  fs::create_directories(dir / "empty");
  expectRefused(run({"inject", "--ct", kCt, "--scene", scene, "--out", out.string(), "--labels", (dir / "empty").string()}),
                {"--labels " + (dir / "empty").string() + ": "}, out);
}

// darcy: more than 100 values in a sweep (1e5 porosities ran past any wait) names the option; a model option the
// simulation refuses (a fixed time step of 5 s, far past the overdamped limit of about 0.1 s) is named in the line;
// a sweep in which no run converged (5 steps) leaves no permeability.csv and no folder.
TEST(HostileCommandLine, DarcySweepsAndModelOptionsNameTheOption) {
  const fs::path out = scratch("darcy") / "out";
  std::string porosities = "0.5";
  for (int k = 1; k <= 100; ++k) porosities += "," + std::to_string(0.5 + 1e-4 * k);
  expectRefused(run({"darcy", "--out", out.string(), "--porosities", porosities}), {"--porosities: 101 values", "100"}, out);
  const std::vector<std::string> small{"darcy", "--out", out.string(), "--porosities", "0.8", "--spacings-mm", "1",
                                       "--viscosities-pa-s", "10", "--lattice", "5", "--no-plot"};
  std::vector<std::string> step = small;
  step.insert(step.end(), {"--max-steps-per-force", "20000", "--time-step-s", "5"});
  const ProgramRun r = run(step);
  EXPECT_EQ(r.exitCode, 1) << r.err;
  EXPECT_NE(r.err.find("cementsph darcy: error: --time-step-s 5: time step 5 s exceeds"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out)) << "a refused model option left its folder";
  std::vector<std::string> fewSteps = small;
  fewSteps.insert(fewSteps.end(), {"--max-steps-per-force", "5"});
  const ProgramRun f = run(fewSteps);
  EXPECT_EQ(f.exitCode, 2) << f.err;
  EXPECT_NE(f.err.find("none of the 1 runs converged within --max-steps-per-force 5"), std::string::npos) << f.err;
  EXPECT_FALSE(fs::exists(out)) << "a sweep with no converged run left its folder";
}

// plan chooses the volume between --min-volume-ml and --max-volume-ml: when every injection fails because the
// pores hold less than the volume (a 12 mm foam block holds about 2.3 ml; 5 ml asked), the line names those
// options, not inject's --volume-ml, which plan does not have; status 2 (a failed run), no plan written, and the
// trajectory check's warning printed before it is not (main.cpp's HoldWarnings).
TEST(HostileCommandLine, APlanWhoseVolumeTheBoneCannotHoldNamesThePlanOptions) {
  const fs::path dir = scratch("plan-volume"), block = dir / "block", out = dir / "out";
  const ProgramRun phantom = run({"phantom", "--out", block.string(), "--size-mm", "12", "--cell-size-mm", "3", "--shell-mm",
                                  "0", "--air-margin-mm", "1", "--volume-ml", "0.1", "--quiet"});
  ASSERT_EQ(phantom.exitCode, 0) << phantom.err;
  const std::string scene = writeText(dir / "scene.json", R"({"tip_mm": [6.345, 6.345, 7.25], "volume_ml": 0.05})");
  const ProgramRun r = run({"plan", "--ct", (block / "pre.nrrd").string(), "--scene", scene, "--out", out.string(),
                            "--entry-mm", "6.3,6.3,1", "--target-mm", "6.345,6.345,7.25", "--max-evaluations", "6",
                            "--starts", "1", "--min-volume-ml", "4", "--max-volume-ml", "5", "--quiet"});
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("(--min-volume-ml .. --max-volume-ml)"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("--volume-ml)"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "plan.json"));
  // The block has no vertebra, so the trajectory check warns ("plan: warning: no target vertebra ..."): held while
  // the run goes on and dropped when it fails (the one line above); under --verbose it comes before the error.
  std::vector<std::string> verbose{"--verbose", "plan", "--ct", (block / "pre.nrrd").string(), "--scene", scene, "--out",
                                   out.string(), "--entry-mm", "6.3,6.3,1", "--target-mm", "6.345,6.345,7.25",
                                   "--max-evaluations", "6", "--starts", "1", "--min-volume-ml", "4", "--max-volume-ml", "5",
                                   "--quiet"};
  const ProgramRun v = run(verbose);
  EXPECT_EQ(v.exitCode, 2) << v.err;
  const std::size_t warning = v.err.find("plan: warning: "), error = v.err.find("cementsph plan: error: ");
  EXPECT_NE(warning, std::string::npos) << v.err;
  EXPECT_LT(warning, error) << v.err;
}

// An unsigned option (phantom --seed) given a negative number or one past 64 bits is refused: CLI11 read '-1' as
// 2^64 - 1 (the phantom recorded seed 18446744073709551615) and saturated 2^64 to the same.
TEST(HostileCommandLine, ANegativeNumberForAnUnsignedOptionIsRefused) {
  const fs::path out = scratch("seed") / "out";
  expectRefused(run({"phantom", "--out", out.string(), "--seed", "-1"}), {"--seed", "'-1' is negative"}, out);
  // 2^64 saturated to 2^64 - 1 silently.
  expectRefused(run({"phantom", "--out", out.string(), "--seed", "18446744073709551616"}), {"--seed", "too large"}, out);
}
