#include "cementsph/study/StudyPlots.h"

#include "cementsph/study/StudyReport.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace cementsph::study {

namespace {

using rendering::PlotSeries;

const std::array<std::array<unsigned char, 3>, 6> kPalette{
    {{31, 119, 180}, {255, 127, 14}, {44, 160, 44}, {148, 103, 189}, {140, 86, 75}, {227, 119, 194}}};

} // namespace

rendering::PlotSpec errorVsWallTimeSpec(const std::vector<StudyRow>& rows) {
  rendering::PlotSpec spec;
  spec.title = "Error against wall time (labels: particle radius, mm)";
  spec.xLabel = "wall time (s)";
  spec.yLabel = "surface error against the reference (mm)";
  spec.logX = true;
  // One series per integrator, in order of first appearance; points from coarse to fine particles.
  std::vector<std::string> integrators;
  for (const StudyRow& r : rows)
    if (std::find(integrators.begin(), integrators.end(), r.spec.integrator) == integrators.end())
      integrators.push_back(r.spec.integrator);
  double maxError = 0.0;
  for (std::size_t k = 0; k < integrators.size(); ++k) {
    std::vector<const StudyRow*> points;
    for (const StudyRow& r : rows)
      if (r.spec.integrator == integrators[k] && r.ok() && r.errors.surfaceErrorMm && r.wallTimeS > 0)
        points.push_back(&r);
    if (points.empty()) continue;
    std::stable_sort(points.begin(), points.end(), [](const StudyRow* a, const StudyRow* b) {
      return a->spec.particleRadiusMm > b->spec.particleRadiusMm;
    });
    PlotSeries s;
    s.name = integrators[k];
    s.style = points.size() > 1 ? PlotSeries::Style::LineAndPoints : PlotSeries::Style::Points;
    s.rgb = kPalette[k % kPalette.size()];
    for (const StudyRow* r : points) {
      s.x.push_back(r->wallTimeS);
      s.y.push_back(*r->errors.surfaceErrorMm);
      s.pointLabels.push_back(radiusLabel(r->spec.particleRadiusMm) + (r->spec.reference ? " (ref.)" : ""));
      maxError = std::max(maxError, *r->errors.surfaceErrorMm);
    }
    spec.series.push_back(s);
  }
  if (spec.series.empty()) throw std::runtime_error("error_vs_wall_time: no run has a surface error to plot");
  // Room around the points for their labels (right) and the legend (top right): wall time padded by
  // factors on its log axis, the error from 0 (the reference) to 1.3x the largest. A flat set of errors
  // (all 0) keeps VTK's own range.
  double minWall = HUGE_VAL, maxWall = 0.0;
  for (const PlotSeries& s : spec.series)
    for (double t : s.x) {
      minWall = std::min(minWall, t);
      maxWall = std::max(maxWall, t);
    }
  spec.xMin = minWall / 1.5;
  spec.xMax = maxWall * 2.0;
  if (maxError > 0) {
    spec.yMin = 0.0;
    spec.yMax = 1.3 * maxError;
  }
  return spec;
}

rendering::PlotSpec spreadingVsViscositySpec(const std::vector<StudyRow>& rows) {
  rendering::PlotSpec spec;
  spec.title = "Mean spreading distance against viscosity";
  spec.xLabel = "viscosity (Pa.s)";
  spec.yLabel = "mean spreading distance (mm)";
  PlotSeries particles, ct;
  particles.name = "particles (mean distance from the tip)";
  particles.rgb = kPalette[0];
  ct.name = "simulated CT, segmented (voxel centres)";
  ct.rgb = kPalette[1];
  for (const StudyRow& r : rows) {
    if (!r.ok()) continue;
    particles.x.push_back(r.spec.viscosityPaS);
    particles.y.push_back(r.particleSpreadingMm);
    if (r.cementFound) {
      ct.x.push_back(r.spec.viscosityPaS);
      ct.y.push_back(r.cementSpreadingMm);
    }
  }
  if (particles.x.empty()) throw std::runtime_error("spreading_vs_viscosity: no run finished");
  double maxSpread = 0.0, maxViscosity = 0.0;
  for (PlotSeries* s : {&particles, &ct}) {
    if (s->x.empty()) continue;
    s->style = s->x.size() > 1 ? PlotSeries::Style::LineAndPoints : PlotSeries::Style::Points;
    s->width = 2.5;
    for (std::size_t i = 0; i < s->x.size(); ++i) {
      maxSpread = std::max(maxSpread, s->y[i]);
      maxViscosity = std::max(maxViscosity, s->x[i]);
    }
    spec.series.push_back(*s);
  }
  // Both axes from 0, as the paper's Fig. 8, with room for the legend above the curves.
  spec.xMin = 0.0;
  spec.xMax = 1.05 * maxViscosity;
  if (maxSpread > 0) {
    spec.yMin = 0.0;
    spec.yMax = 1.3 * maxSpread;
  }
  return spec;
}

rendering::PlotSpec endPressureVsViscositySpec(const std::vector<StudyRow>& rows) {
  // Normalised by the largest end pressure of the sweep, as the paper's Fig. 9 normalises its pressures: the
  // figure compares how pressure rises with viscosity, which a model's absolute pressure scale does not change.
  double largest = 0.0, maxViscosity = 0.0;
  for (const StudyRow& r : rows)
    if (r.ok() && std::isfinite(r.finalTipPressurePa)) largest = std::max(largest, r.finalTipPressurePa);
  if (!(largest > 0.0)) throw std::runtime_error("end_pressure_vs_viscosity: no run ended with a positive outlet pressure");
  rendering::PlotSpec spec;
  // One series, so XYPlot draws no legend: the title says what it is (simulated; no experiment here).
  spec.title = "Simulated outlet pressure at the end of injection, normalised (paper Fig. 9)";
  spec.xLabel = "viscosity (Pa.s)";
  spec.yLabel = "end pressure / largest end pressure";
  PlotSeries simulated;
  simulated.name = "simulated (this study; no experiment given)";
  simulated.rgb = kPalette[0];
  for (const StudyRow& r : rows) {
    if (!r.ok() || !std::isfinite(r.finalTipPressurePa)) continue;
    simulated.x.push_back(r.spec.viscosityPaS);
    simulated.y.push_back(r.finalTipPressurePa / largest);
    maxViscosity = std::max(maxViscosity, r.spec.viscosityPaS);
  }
  simulated.style = simulated.x.size() > 1 ? PlotSeries::Style::LineAndPoints : PlotSeries::Style::Points;
  simulated.width = 2.5;
  spec.series.push_back(simulated);
  // Both axes from 0, as Fig. 8 and 9; room above 1 for the legend.
  spec.xMin = 0.0;
  spec.xMax = 1.05 * maxViscosity;
  spec.yMin = 0.0;
  spec.yMax = 1.3;
  return spec;
}

std::string endPressureCaption() {
  return "the outlet (tip) pressure at the end of injection of each run of the viscosity sweep, divided by the "
         "largest of them, against the cement's viscosity: the simulated half of the paper's Fig. 9 "
         "(\"Normalized outlet cement pressure compared between experiments and simulations\"; Basafa et al. 2013). "
         "No experimental pressures are read, so there is no experimental series.";
}

void writeEndPressureVsViscosityPlot(const std::vector<StudyRow>& rows, const std::filesystem::path& png) {
  rendering::writePlotPng(endPressureVsViscositySpec(rows), png);
}

void writeErrorVsWallTimePlot(const std::vector<StudyRow>& rows, const std::filesystem::path& png) {
  rendering::writePlotPng(errorVsWallTimeSpec(rows), png);
}

void writeSpreadingVsViscosityPlot(const std::vector<StudyRow>& rows, const std::filesystem::path& png) {
  rendering::writePlotPng(spreadingVsViscositySpec(rows), png);
}

} // namespace cementsph::study
