#include "cementsph/rendering/ProjectedAreaPlot.h"

#include "cementsph/rendering/XYPlot.h"

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
  for (const ProjectedAreaSeries& s : series) {
    PlotSeries p;
    p.name = s.name;
    p.x = s.timeS;
    p.y = s.areaMm2;
    p.rgb = s.rgb;
    p.style = s.timeS.size() > 1 ? PlotSeries::Style::LineAndPoints : PlotSeries::Style::Points;
    spec.series.push_back(p);
  }
  writePlotPng(spec, png);
}

} // namespace cementsph::rendering
