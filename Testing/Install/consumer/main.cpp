// Runs the checks of the components this consumer was configured with (CONSUMER_GROUP); exit 0 when all pass.
#include "Checks.h"

#include <cmath>
#include <cstdio>

int compare(const char* name, double got, double expected, double tolerance) {
  const bool ok = std::abs(got - expected) <= tolerance;
  std::printf("%s: %.12g (expected %.12g, tolerance %.3g) %s\n", name, got, expected, tolerance, ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}

// A component exposes only its own headers (include/CementSPH/<component>) and those of the components it
// links publicly: SPH's consumer cannot see DRR's or ImagingIO's, ImagingIO's cannot see SPH's, and DRR's
// cannot see SurfaceMetrics' (which DRR links privately) nor ImagingIO's.
#if defined(CONSUMER_GROUP_SPH) && (__has_include("cementsph/drr/DRRGeometry.h") || __has_include("cementsph/imaging/VolumeIO.h"))
#error "the SPH component's include folders expose other modules' headers"
#endif
#if defined(CONSUMER_GROUP_IMAGINGIO) && __has_include("cementsph/sph/Kernels.h")
#error "the ImagingIO component's include folders expose SPH's headers"
#endif
#if defined(CONSUMER_GROUP_DRR) && (__has_include("cementsph/surfacemetrics/VolumeMetrics.h") || __has_include("cementsph/imaging/VolumeIO.h"))
#error "the DRR component's include folders expose SurfaceMetrics' or ImagingIO's headers"
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
