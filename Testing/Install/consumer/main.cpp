// Runs the checks of the components this consumer was configured with (CONSUMER_GROUP); exit 0 when all pass.
#include "Checks.h"

#include <cmath>
#include <cstdio>

int compare(const char* name, double got, double expected, double tolerance) {
  const bool ok = std::abs(got - expected) <= tolerance;
  std::printf("%s: %.12g (expected %.12g, tolerance %.3g) %s\n", name, got, expected, tolerance, ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}

#if defined(CONSUMER_GROUP_SPH)
// A component exposes only its own headers (include/CementSPH/<component>): SPH's consumer cannot see DRR's.
#if __has_include("cementsph/drr/DRRGeometry.h")
#error "the SPH component's include folder exposes DRR's headers"
#endif
#endif

int main() {
  int failures = 0;
#if defined(CONSUMER_GROUP_SPH)
  failures += checkSph();
#elif defined(CONSUMER_GROUP_IMAGINGIO)
  failures += checkImagingIO();
#elif defined(CONSUMER_GROUP_CTSCENE)
  failures += checkCTScene();
#elif defined(CONSUMER_GROUP_DRR)
  failures += checkDrr();
#elif defined(CONSUMER_GROUP_ALL)
  failures += checkSph() + checkDrr() + checkCaseFarm();
#endif
  std::printf("%s\n", failures == 0 ? "consumer checks passed" : "consumer checks FAILED");
  return failures == 0 ? 0 : 1;
}
