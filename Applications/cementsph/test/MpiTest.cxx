// Studies and plans over MPI ranks (issue "Planning at scale", item 4), run as a user would:
// `mpirun --allow-run-as-root --oversubscribe -n N cementsph study|plan ...` against the same command in
// one process. The oracle is the serial run: every row and every number the same (wall times and the
// rank column aside), and the report records the ranks. A rank made to fail (CEMENTSPH_FAIL_RANK) loses
// only its own cases: they are reported failed with the reason, and the other ranks' rows are still the
// serial run's. Bad input under mpirun is one line from rank 0 and exit 1.
#include "PhantomTip.h"
#include "ProgramRun.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace {

const fs::path kData = CEMENTSPH_TEST_DATA_DIR;

fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / name;
  fs::remove_all(p);
  return p;
}

cementsph::testing::ProgramRun serial(std::vector<std::string> args) {
  return cementsph::testing::runProgram(CEMENTSPH_EXECUTABLE, args);
}

cementsph::testing::ProgramRun underMpirun(int ranks, std::vector<std::string> args) {
  std::vector<std::string> all{"-q", "--allow-run-as-root", "--oversubscribe", "-n", std::to_string(ranks),
                               CEMENTSPH_EXECUTABLE};
  all.insert(all.end(), args.begin(), args.end());
  return cementsph::testing::runProgram(CEMENTSPH_MPIEXEC, all);
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A CSV as rows of column -> text (the failure column is quoted, commas inside it are kept).
std::vector<std::map<std::string, std::string>> readCsv(const fs::path& p) {
  std::istringstream in(slurp(p));
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> fields;
    std::string field;
    bool quoted = false;
    for (char c : line) {
      if (c == '"') quoted = !quoted;
      else if (c == ',' && !quoted) fields.push_back(field), field.clear();
      else field += c;
    }
    fields.push_back(field);
    if (header.empty()) {
      header = fields;
      continue;
    }
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < fields.size(); ++i) row[header[i]] = fields[i];
    rows.push_back(row);
  }
  return rows;
}

// The figures that do not depend on where or how fast a run ran.
std::map<std::string, std::string> figures(std::map<std::string, std::string> row) {
  for (const char* timing : {"wall_time_s", "real_time_factor", "analysis_time_s", "rank"}) row.erase(timing);
  return row;
}

std::string phantomTip() { return cementsph::testing::foamPhantomTipArgument(kData); }

// Four size-study runs (the reference first) and two viscosities, tiny injections into the phantom.
std::vector<std::string> studyArgs(const fs::path& out) {
  return {"study",         "--ct",         (kData / "foam-phantom" / "pre.nrrd").string(),
          "--scene",       (kData / "scenes" / "paper-1ml.json").string(),
          "--tip-mm",      phantomTip(),
          "--volume-ml",   "0.03",
          "--radii-mm",    "1.0,0.75",
          "--integrators", "overdamped,central-difference",
          "--viscosities-pa-s", "100,400",
          "--no-pictures", "--out", out.string()};
}

// The serial study each test compares with, in a folder of its own (ctest -j runs the tests side by side).
class MpiStudy : public ::testing::Test {
protected:
  void SetUp() override {
    setenv("OMP_NUM_THREADS", "1", 1); // one thread per rank on the 2 shared cores
    const fs::path out =
        scratch(std::string("mpi-study-serial-") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    const auto r = serial(studyArgs(out));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    serialSize_ = readCsv(out / "study.csv");
    serialViscosity_ = readCsv(out / "spreading_vs_viscosity.csv");
    ASSERT_EQ(serialSize_.size(), 4u);
    ASSERT_EQ(serialViscosity_.size(), 2u);
  }
  std::vector<std::map<std::string, std::string>> serialSize_, serialViscosity_;
};

void expectSameAsSerial(const std::vector<std::map<std::string, std::string>>& rows,
                        const std::vector<std::map<std::string, std::string>>& serialRows, int ranks) {
  ASSERT_EQ(rows.size(), serialRows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(figures(rows[i]), figures(serialRows[i])) << "row " << i + 1;
    EXPECT_EQ(serialRows[i].at("rank"), "0");
    const int rank = std::stoi(rows[i].at("rank"));
    EXPECT_GE(rank, 1) << "rank 0 coordinates; the workers inject";
    EXPECT_LT(rank, ranks);
  }
}

} // namespace

TEST_F(MpiStudy, TwoAndThreeRanksGiveTheSerialRows) {
  for (int ranks : {2, 3}) {
    const fs::path out = scratch("mpi-study-" + std::to_string(ranks));
    const auto r = underMpirun(ranks, studyArgs(out));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    expectSameAsSerial(readCsv(out / "study.csv"), serialSize_, ranks);
    expectSameAsSerial(readCsv(out / "spreading_vs_viscosity.csv"), serialViscosity_, ranks);
    std::ifstream j(out / "study.json");
    EXPECT_EQ(nlohmann::json::parse(j).at("mpi_ranks").get<int>(), ranks);
    if (ranks == 3) { // two workers, six runs: both took a share
      std::set<std::string> used;
      for (const auto& row : readCsv(out / "study.csv")) used.insert(row.at("rank"));
      for (const auto& row : readCsv(out / "spreading_vs_viscosity.csv")) used.insert(row.at("rank"));
      EXPECT_EQ(used, (std::set<std::string>{"1", "2"}));
    }
  }
}

TEST_F(MpiStudy, AFailingRankLosesOnlyItsOwnCases) {
  const fs::path out = scratch("mpi-study-fail");
  setenv("CEMENTSPH_FAIL_RANK", "2", 1);
  const auto r = underMpirun(3, studyArgs(out));
  unsetenv("CEMENTSPH_FAIL_RANK");
  EXPECT_EQ(r.exitCode, 3) << r.err; // some runs failed: the study's own status for that
  auto rows = readCsv(out / "study.csv");
  const auto sweep = readCsv(out / "spreading_vs_viscosity.csv");
  ASSERT_EQ(rows.size(), serialSize_.size());
  ASSERT_EQ(sweep.size(), serialViscosity_.size());
  std::vector<std::map<std::string, std::string>> serialRows = serialSize_;
  serialRows.insert(serialRows.end(), serialViscosity_.begin(), serialViscosity_.end());
  rows.insert(rows.end(), sweep.begin(), sweep.end());
  std::size_t ok = 0, failed = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].at("rank") == "2") {
      ++failed;
      EXPECT_EQ(rows[i].at("status"), "failed");
      EXPECT_NE(rows[i].at("failure").find("rank 2"), std::string::npos) << rows[i].at("failure");
    } else {
      ++ok;
      EXPECT_EQ(rows[i].at("rank"), "1");
      // Rank 1's rows are the serial run's (their errors against the reference too, when rank 1 ran it).
      auto mine = figures(rows[i]), expected = figures(serialRows[i]);
      if (rows[0].at("status") != "ok")
        for (const char* e : {"surface_error_mm", "hausdorff95_mm", "dice", "spreading_difference_mm"})
          mine.erase(e), expected.erase(e);
      EXPECT_EQ(mine, expected) << "row " << i;
    }
  }
  EXPECT_GE(ok, 1u);  // rank 1 was handed the first run
  EXPECT_GE(failed, 1u);
  EXPECT_NE(r.err.find("failed: rank 2: failed on purpose"), std::string::npos) << r.err;
}

TEST(MpiPlan, ThreeRanksGiveTheSerialPlanOnTheVertebra) {
  setenv("OMP_NUM_THREADS", "1", 1);
  auto args = [](const fs::path& out) {
    return std::vector<std::string>{
        "plan", "--ct", (kData / "vertebra-phantom" / "pre.nrrd").string(), "--scene", (kData / "scenes" / "paper.json").string(),
        "--entry-mm", "48.5,52.4,22.5", "--min-depth-mm", "10", "--max-depth-mm", "36",
        "--target-mm", "32,21,22.5", "--target-radius-mm", "6", "--min-volume-ml", "1", "--max-volume-ml", "4",
        "--max-syringe-mpa", "3", "--max-leakage-ml", "0", "--quiet", "--out", out.string()};
  };
  const fs::path one = scratch("mpi-plan-serial"), three = scratch("mpi-plan-3");
  const auto rs = serial(args(one));
  ASSERT_EQ(rs.exitCode, 0) << rs.err;
  const auto rm = underMpirun(3, args(three));
  ASSERT_EQ(rm.exitCode, 0) << rm.err;
  std::ifstream a(one / "plan.json"), b(three / "plan.json");
  const auto p1 = nlohmann::json::parse(a), p3 = nlohmann::json::parse(b);
  EXPECT_EQ(p1.at("evaluations"), p3.at("evaluations"));
  EXPECT_EQ(p1.at("best"), p3.at("best"));
  EXPECT_EQ(p1.at("mpi_ranks").get<int>(), 1);
  EXPECT_EQ(p3.at("mpi_ranks").get<int>(), 3);
  EXPECT_EQ(slurp(one / "plan.csv"), slurp(three / "plan.csv"));
  std::set<int> ranks;
  for (const auto& s : p3.at("starts")) ranks.insert(s.at("rank").get<int>());
  EXPECT_EQ(ranks, (std::set<int>{1, 2}));
  // The plan itself: the tip in the 6 mm target, no leak, under 3 MPa.
  const auto& best = p3.at("best");
  const double dx = best["tip_mm"][0].get<double>() - 32, dy = best["tip_mm"][1].get<double>() - 21,
               dz = best["tip_mm"][2].get<double>() - 22.5;
  EXPECT_LT(std::sqrt(dx * dx + dy * dy + dz * dz), 6.0);
  EXPECT_TRUE(best.at("within_limits").get<bool>());
  EXPECT_DOUBLE_EQ(best.at("leakage_volume_ml").get<double>(), 0.0);
  EXPECT_LT(best.at("max_syringe_pressure_mpa").get<double>(), 3.0);
}

TEST(MpiPlan, BadInputUnderMpirunIsOneLineFromRankZero) {
  const fs::path out = scratch("mpi-plan-bad");
  const auto r = underMpirun(
      3, {"plan", "--ct", (kData / "vertebra-phantom" / "pre.nrrd").string(), "--scene", (kData / "scenes" / "paper.json").string(),
          "--entry-mm", "41,49.08,22.5", "--direction", "-0.3,-0.954,0", "--max-depth-mm", "200", "--target-mm",
          "32,21,22.5", "--out", out.string()});
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.rfind("cementsph plan: error: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("leaves the CT"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}
