#pragma once
// Where a test suite finds the source tree's Data/, the build folder, the cementsph program and the reference
// pictures. Every suite gets this header by `-include` (cmake/CementSPHTesting.cmake), and the paths come from one
// compiled file, TestPaths.cpp. Why not -D strings on each suite's compile line, as before: an absolute path on a
// compile line is part of ccache's key, so in a clone at another path (CI's clean clone) every suite missed the
// cache and compiled cold; now only TestPaths.cpp does.
namespace cementsph::testing {
const char* testDataDir();   // <source>/Data
const char* binaryDir();     // the build folder
const char* programPath();   // the cementsph launcher
const char* baselineDir();   // <source>/Testing/Data/Baselines
}  // namespace cementsph::testing

#define CEMENTSPH_TEST_DATA_DIR (::cementsph::testing::testDataDir())
#define CEMENTSPH_BINARY_DIR (::cementsph::testing::binaryDir())
#define CEMENTSPH_EXECUTABLE (::cementsph::testing::programPath())
#define CEMENTSPH_EXE (::cementsph::testing::programPath())
// Only the suites that compare with reference pictures ask for it (RenderingTestSupport.h's kBaselineDir).
#ifdef CEMENTSPH_WITH_BASELINES
#define CEMENTSPH_BASELINE_DIR (::cementsph::testing::baselineDir())
#endif
