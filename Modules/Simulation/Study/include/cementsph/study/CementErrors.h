// The errors of one simulated cement against a reference cement, as the paper scores a simulation against
// post-operative CT (Basafa et al. 2013, "Comparison with experiments", Figs. 6-8):
//   surface error      the paper's error: mean distance from the vertices of one isosurface to the other
//                      surface, the larger of the two directions (SurfaceDistance.h), mm
//   Hausdorff 95 %     the larger of the two directed 95th percentiles, mm
//   Dice               2|A and B| / (|A| + |B|) of the two masks (on one grid)
//   spreading diff.    mean spreading distance of the run minus that of the reference, mm (signed)
// Every figure is optional: it is absent when it cannot be computed (no cement found in one of the two);
// nothing is ever NaN.
#pragma once

#include "cementsph/study/AnalysedCement.h"

#include <optional>

namespace cementsph::study {

struct CementErrors {
  std::optional<double> surfaceErrorMm;
  std::optional<double> hausdorff95Mm;
  std::optional<double> dice;
  std::optional<double> spreadingDifferenceMm;
};

// Both cements must be on one grid (throws std::invalid_argument otherwise). The surfaces get the
// per-vertex distance array (SurfaceDistance.h) in place. Against itself every error is exactly 0 and
// Dice exactly 1: a vertex's nearest point on its own surface is itself.
CementErrors cementErrors(const AnalysedCement& run, const AnalysedCement& reference);

} // namespace cementsph::study
