#include "cementsph/study/CementErrors.h"

#include "cementsph/surfacemetrics/SurfaceDistance.h"

namespace cementsph::study {

CementErrors cementErrors(const AnalysedCement& run, const AnalysedCement& reference) {
  CementErrors e;
  // Dice is defined for empty masks too (0 if one is empty, 1 if both are), and checks the grids.
  e.dice = surfacemetrics::overlap(run.vtkMask, reference.vtkMask).dice;
  if (!run.found() || !reference.found()) return e;
  e.spreadingDifferenceMm = run.spreadingMm - reference.spreadingMm;
  if (run.surface && reference.surface && run.surface->GetNumberOfPolys() > 0 &&
      reference.surface->GetNumberOfPolys() > 0) {
    const surfacemetrics::SurfaceComparison s = surfacemetrics::compareSurfaces(run.surface, reference.surface);
    e.surfaceErrorMm = s.errorMm;
    e.hausdorff95Mm = s.hausdorff95Mm;
  }
  return e;
}

} // namespace cementsph::study
