// Results do not depend on the thread count (BENCHMARKS.md): `cementsph inject` on the bundled phantom, 0.3 ml
// of the paper's plan, with --threads 1 and --threads 2. The phantom's ROI holds ~260k fixed particles, so the
// table of fixed-particle sums, the porous solid and the voxeliser all run shared out at 2 threads.
// Oracle: the 1-thread run. Tolerance: bitwise (every sum is gathered per particle or per table node in a
// fixed order, whoever computes it; measured identical): the final particles, simulated_ct.nrrd voxel for voxel,
// the tip-pressure series and every metric but wall times.
#include "ProgramRun.h"

#include "cementsph/imaging/PolyDataIO.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <vtkPolyData.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace {

fs::path injectWithThreads(int threads, const std::string& pressureModel) {
  const fs::path data = CEMENTSPH_TEST_DATA_DIR;
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / ("threads-" + pressureModel + "-" + std::to_string(threads));
  fs::remove_all(out);
  const auto r = cementsph::testing::runProgram(
      CEMENTSPH_EXECUTABLE, {"inject", "--ct", (data / "foam-phantom" / "pre.nrrd").string(), "--scene",
                             (data / "scenes" / "paper-1ml.json").string(), "--tip-mm", "22.325,21.855,21.75", "--set",
                             "volume_ml=0.3", "--set", "pressure_model=\"" + pressureModel + "\"", "--threads", std::to_string(threads), "--no-pictures", "--quiet",
                             "--out", out.string()});
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return out;
}

nlohmann::json metricsWithoutTimes(const fs::path& dir) {
  std::ifstream in(dir / "metrics.json");
  nlohmann::json m = nlohmann::json::parse(in);
  for (const char* k : {"wall_time_s", "real_time_factor", "threads", "pressure_solve_wall_s", "pressure_assembly_wall_s",
                        "provenance" /* its command line names the thread count */})
    m.erase(k);
  return m;
}

std::string text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

} // namespace

// Both the particle model (the paper's equation of state) and the default voxel-grid Darcy filling.
class ThreadCount : public ::testing::TestWithParam<std::string> {};

TEST_P(ThreadCount, InjectOnThePhantomGivesTheSameResultOnOneAndTwoThreads) {
  const fs::path one = injectWithThreads(1, GetParam()), two = injectWithThreads(2, GetParam());
  const nlohmann::json m1 = metricsWithoutTimes(one), m2 = metricsWithoutTimes(two);
  EXPECT_EQ(m1, m2) << m1.dump(1) << "\n" << m2.dump(1);
  // Big enough to share out: 10^5 fixed particles, or 10^5 voxels in the region.
  const auto& roi = m1.at("roi_voxels");
  ASSERT_GT(std::max(m1.value("fixed_particles", 0.0),
                     roi[0].get<double>() * roi[1].get<double>() * roi[2].get<double>()), 1e5);
  EXPECT_EQ(text(one / "tip_pressure.csv"), text(two / "tip_pressure.csv"));

  char last[64];
  std::snprintf(last, sizeof last, "particles_%04d.vtp", m1.at("snapshots").get<int>() - 1);
  const auto p1 = cementsph::imaging::readPolyData((one / last).string());
  const auto p2 = cementsph::imaging::readPolyData((two / last).string());
  ASSERT_EQ(p1->GetNumberOfPoints(), p2->GetNumberOfPoints());
  ASSERT_GT(p1->GetNumberOfPoints(), 100);
  std::size_t differing = 0;
  for (vtkIdType i = 0; i < p1->GetNumberOfPoints(); ++i)
    for (int a = 0; a < 3; ++a) differing += p1->GetPoint(i)[a] != p2->GetPoint(i)[a];
  EXPECT_EQ(differing, 0u);

  const auto ct1 = cementsph::imaging::readVolume((one / "simulated_ct.nrrd").string());
  const auto ct2 = cementsph::imaging::readVolume((two / "simulated_ct.nrrd").string());
  const std::size_t n = ct1->GetLargestPossibleRegion().GetNumberOfPixels();
  ASSERT_EQ(n, ct2->GetLargestPossibleRegion().GetNumberOfPixels());
  std::size_t voxels = 0;
  for (std::size_t i = 0; i < n; ++i) voxels += ct1->GetBufferPointer()[i] != ct2->GetBufferPointer()[i];
  EXPECT_EQ(voxels, 0u);
}

INSTANTIATE_TEST_SUITE_P(PressureModels, ThreadCount, ::testing::Values("equation-of-state", "voxel-darcy"),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           return p.param == "voxel-darcy" ? std::string("VoxelDarcy") : std::string("EquationOfState");
                         });
