// The one file whose compile line carries the absolute paths (see TestPaths.h for why).
#include "TestPaths.h"

namespace cementsph::testing {
const char* testDataDir() { return CEMENTSPH_PATH_DATA; }
const char* binaryDir() { return CEMENTSPH_PATH_BINARY; }
const char* programPath() { return CEMENTSPH_PATH_PROGRAM; }
const char* baselineDir() { return CEMENTSPH_PATH_BASELINES; }
}  // namespace cementsph::testing
