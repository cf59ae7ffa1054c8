// RunEstimate's memory figure for the voxel-grid Darcy filling against a measurement, not against its own
// constant: the run's peak resident memory, measured by the kernel (VmHWM of /proc/self/status, reset with
// clear_refs before the run), in a fork()ed child so that nothing else of the test process counts.
// The estimate guards runs that would not fit in memory; it must be neither far below what a run takes
// (a run the estimate lets through could exhaust memory) nor far above it (it would refuse runs that fit):
// within a factor 1.5 of the measured peak.
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/scene/RunEstimate.h"
#include "cementsph/scene/SceneConfig.h"
#include "ScaffoldCT.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace {

using namespace cementsph::scene;

// A /proc/self/status field in kB, or -1.
long statusKb(const std::string& field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(field + ":", 0) == 0) return std::stol(line.substr(field.size() + 1));
  return -1;
}

TEST(RunEstimateMemory, TheVoxelModelsEstimateIsWithinOneAndAHalfOfTheMeasuredPeak) {
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer's shadow memory, redzones and quarantine make the process's peak 2-3x what the run itself needs
  // (273.7 MB measured against 102 MB estimated in CI's ASan tree): the oracle holds for a plain build only.
  GTEST_SKIP() << "the measured peak of an AddressSanitizer build is not the run's memory";
#endif
  // A uniform trabecular CT (200 HU) of 120^3 voxels of 0.5 mm; the scene's 40 mm region is 80^3 = 512 000
  // voxels, 0.3 ml of cement: a run whose arrays dwarf the cement's own.
  const auto ct = cementsph::scene::testing::cube(120, 0.5, 200.f);
  SceneConfig scene = sceneFromJson({{"tip_mm", {30, 30, 30}},
                                     {"volume_ml", 0.3},
                                     {"roi_size_mm", 40},
                                     {"cannula_length_mm", 5}});
  const RunEstimate e = estimateRun(scene, 0.125);
  ASSERT_TRUE(e.voxelDarcy);
  ASSERT_NEAR(e.voxels, 512000.0, 1.0);

  int pipeFd[2];
  ASSERT_EQ(pipe(pipeFd), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(pipeFd[0]);
    long peakKb = -1, baseKb = -1;
    {
      std::ofstream("/proc/self/clear_refs") << "5"; // resets VmHWM to the current resident size
      baseKb = statusKb("VmRSS");
      InjectionRunOptions o; // no files: the arrays of the run only
      (void)runInjection(ct.GetPointer(), scene, o);
      peakKb = statusKb("VmHWM");
    }
    const long delta = peakKb >= 0 && baseKb >= 0 ? peakKb - baseKb : -1;
    (void)!write(pipeFd[1], &delta, sizeof delta);
    _exit(0);
  }
  close(pipeFd[1]);
  long deltaKb = -1;
  const auto got = read(pipeFd[0], &deltaKb, sizeof deltaKb);
  close(pipeFd[0]);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_EQ(got, long(sizeof deltaKb));
  ASSERT_GT(deltaKb, 0);
  const double measured = double(deltaKb) * 1024.0;
  RecordProperty("measured_peak_bytes", std::to_string(measured));
  RecordProperty("estimated_bytes", std::to_string(e.voxelMemoryBytes));
  std::printf("measured peak %.1f MB, estimate %.1f MB (%.0f bytes per region voxel measured)\n", measured / 1e6,
              e.voxelMemoryBytes / 1e6, measured / e.voxels);
  EXPECT_GT(e.voxelMemoryBytes, measured / 1.5);
  EXPECT_LT(e.voxelMemoryBytes, measured * 1.5);
}

} // namespace
