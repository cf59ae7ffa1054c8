// `cementsph demo` end to end on the bundled phantom. The phantom's post scan was made by the same model
// with the same plan (truth.json), so simulation and "experiment" differ only by CT noise, the known
// misalignment (registered away) and how each CT's cement is segmented: the surfaces should agree within
// about one voxel diagonal (0.83 mm at 0.47 x 0.47 x 0.5 mm) and overlap with Dice >= 0.8.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>

namespace fs = std::filesystem;

TEST(DemoCommand, RunsTheBundledPipelineAndAgreesWithThePhantom) {
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "demo";
  fs::remove_all(out);
  const std::string cmd = std::string(CEMENTSPH_EXECUTABLE) + " demo --threads 2 --out " + out.string() + " > " +
                          (out.string() + ".log") + " 2>&1";
  fs::create_directories(out.parent_path());
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "see " << out.string() << ".log";
  for (const char* f : {"inject/metrics.json", "inject/simulated_ct.nrrd", "inject/particles.pvd",
                        "inject/tip_pressure.csv", "compare/metrics.json", "compare/surfaces.png",
                        "compare/slices.png", "tip_pressure.png"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  std::ifstream in(out / "compare" / "metrics.json");
  const auto m = nlohmann::json::parse(in);
  EXPECT_LT(m.at("error_mm").get<double>(), 0.83);
  EXPECT_GE(m.at("dice").get<double>(), 0.8);
  std::ifstream inj(out / "inject" / "metrics.json");
  const auto mi = nlohmann::json::parse(inj);
  EXPECT_EQ(mi.at("escaped_particles").get<int>(), 0);
}
