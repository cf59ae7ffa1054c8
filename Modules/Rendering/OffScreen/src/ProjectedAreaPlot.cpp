#include "cementsph/rendering/ProjectedAreaPlot.h"

#include "cementsph/rendering/XYPlot.h"

#include <algorithm>
#include <cmath>

namespace cementsph::rendering {

void writeProjectedAreaPlot(const std::vector<ProjectedAreaSeries>& series, const std::filesystem::path& png,
                            int widthPx, int heightPx) {
  PlotSpec spec;
  spec.title = "Projected cement area over time (X-ray sequence)";
  spec.xLabel = "time (s)";
  spec.yLabel = "projected cement area at the isocentre (mm^2)";
  spec.widthPx = widthPx;
  spec.heightPx = heightPx;
  spec.yMin = 0.0; // areas start from nothing: keep zero on the axis so growth reads true
  double top = 0.0, first = HUGE_VAL, last = -HUGE_VAL;
  for (const ProjectedAreaSeries& s : series) {
    PlotSeries p;
    p.name = s.name;
    p.x = s.timeS;
    p.y = s.areaMm2;
    p.rgb = s.rgb;
    p.style = s.joined && s.timeS.size() > 1 ? PlotSeries::Style::LineAndPoints : PlotSeries::Style::Points;
    if (p.style == PlotSeries::Style::Points) p.width = 4.0; // lone markers must stand out
    spec.series.push_back(p);
    for (double a : s.areaMm2)
      if (std::isfinite(a)) top = std::max(top, a);
    for (double t : s.timeS)
      if (std::isfinite(t)) first = std::min(first, t), last = std::max(last, t);
  }
  // Headroom above the largest area keeps the legend (top right) off the curves' ends; a margin of 3 % of
  // the time span on both sides keeps the first and last markers whole.
  if (top > 0.0) spec.yMax = 1.25 * top;
  if (last > first) {
    spec.xMin = first - 0.03 * (last - first);
    spec.xMax = last + 0.03 * (last - first);
  }
  writePlotPng(spec, png);
}

} // namespace cementsph::rendering
