// Study rows with known figures, for the report and plot tests (no simulation behind them).
#pragma once

#include "cementsph/study/StudyRow.h"

#include <string>
#include <vector>

namespace cementsph::study::testing {

inline StudyRow sizeRow(const std::string& integrator, double radiusMm, double wallS, double errorMm,
                        bool reference = false) {
  StudyRow r;
  r.spec.integrator = integrator;
  r.spec.particleRadiusMm = radiusMm;
  r.spec.reference = reference;
  r.wallTimeS = wallS;
  r.simulatedTimeS = 20.0;
  r.realTimeFactor = 20.0 / wallS;
  r.steps = static_cast<std::size_t>(1000 * wallS);
  const double d = 2 * radiusMm;
  r.expectedParticles = 1000.0 / (d * d * d);
  r.fluidParticles = static_cast<std::size_t>(r.expectedParticles);
  r.fixedParticles = 250000;
  r.volumeInjectedMl = static_cast<double>(r.fluidParticles) * d * d * d / 1000.0;
  r.particleSpreadingMm = 5.0 + errorMm;
  r.cementFound = true;
  r.cementVolumeMl = 1.2;
  r.cementSpreadingMm = 5.5 + errorMm;
  r.errors.surfaceErrorMm = errorMm;
  r.errors.hausdorff95Mm = 2 * errorMm;
  r.errors.dice = 1.0 - errorMm / 2;
  r.errors.spreadingDifferenceMm = errorMm;
  return r;
}

// The paper's five radii with both integrators, errors and times of the order measured on the phantom.
inline std::vector<StudyRow> paperLikeRows() {
  std::vector<StudyRow> rows{sizeRow("central-difference", 0.45, 90.0, 0.0, true)};
  const double radii[] = {1.00, 0.75, 0.57, 0.50, 0.45};
  const double overdampedWall[] = {1.5, 2.2, 3.4, 4.6, 6.1}, overdampedError[] = {1.10, 0.62, 0.31, 0.18, 0.05};
  const double cdWall[] = {12.0, 21.0, 33.0, 55.0}, cdError[] = {1.05, 0.58, 0.27, 0.14};
  for (int i = 0; i < 5; ++i) rows.push_back(sizeRow("overdamped", radii[i], overdampedWall[i], overdampedError[i]));
  for (int i = 0; i < 4; ++i) rows.push_back(sizeRow("central-difference", radii[i], cdWall[i], cdError[i]));
  return rows;
}

inline StudyRow viscosityRow(double viscosityPaS, double spreadingMm) {
  StudyRow r = sizeRow("overdamped", 0.57, 3.0, 0.0);
  r.spec.sweep = StudyRunSpec::Sweep::Viscosity;
  r.spec.viscosityPaS = viscosityPaS;
  r.errors = {};
  r.particleSpreadingMm = spreadingMm;
  r.cementSpreadingMm = spreadingMm + 0.4;
  return r;
}

} // namespace cementsph::study::testing
