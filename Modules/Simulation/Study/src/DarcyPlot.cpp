#include "cementsph/study/DarcyPlot.h"

#include "cementsph/rendering/XYPlot.h"

#include <algorithm>
#include <array>
#include <map>
#include <sstream>
#include <stdexcept>

namespace cementsph::study {

void writeDarcyPlot(const std::vector<sph::DarcyResult>& results, const std::filesystem::path& png) {
  using rendering::PlotSeries;
  rendering::PlotSpec spec;
  spec.title = "Dimensionless permeability k/d^2 against porosity (Eq. 12)";
  spec.xLabel = "porosity";
  spec.yLabel = "k / d^2 (d: particle spacing)";
  spec.logY = true;
  // One series per spacing and viscosity: Darcy's law says they should fall on one curve.
  std::map<std::pair<double, double>, PlotSeries> bySet;
  double lo = 1.0, hi = 0.0;
  for (const sph::DarcyResult& r : results) {
    if (!(r.dimensionlessPermeability > 0)) continue; // not drawable on a log axis
    PlotSeries& s = bySet[{r.input.spacing, r.input.viscosity}];
    if (s.name.empty()) {
      std::ostringstream n;
      n << "SPH, d " << r.input.spacing * 1e3 << " mm, " << r.input.viscosity << " Pa.s";
      s.name = n.str();
      s.style = PlotSeries::Style::LineAndPoints;
    }
    s.x.push_back(r.porosity);
    s.y.push_back(r.dimensionlessPermeability);
    lo = std::min(lo, r.porosity);
    hi = std::max(hi, r.porosity);
  }
  if (bySet.empty()) throw std::runtime_error(png.string() + ": no positive permeability to plot");
  const std::array<std::array<unsigned char, 3>, 6> palette{
      {{31, 119, 180}, {255, 127, 14}, {44, 160, 44}, {148, 103, 189}, {140, 86, 75}, {227, 119, 194}}};
  std::size_t k = 0;
  for (auto& [key, series] : bySet) {
    series.rgb = palette[k++ % palette.size()];
    if (series.x.size() < 2) series.style = PlotSeries::Style::Points; // a line needs two points
    spec.series.push_back(series);
  }
  // Kozeny-Carman with the spacing as grain diameter, over the same porosity range (phi < 1).
  PlotSeries kc;
  kc.name = "Kozeny-Carman, phi^3 / (180 (1 - phi)^2)";
  kc.style = PlotSeries::Style::Line;
  kc.rgb = {0, 0, 0};
  const double top = std::min(hi, 0.95);
  for (int i = 0; i <= 50 && lo < top; ++i) {
    const double phi = lo + (top - lo) * i / 50.0;
    kc.x.push_back(phi);
    kc.y.push_back(sph::kozenyCarmanDimensionless(phi));
  }
  if (kc.x.size() > 1) spec.series.push_back(kc);
  rendering::writePlotPng(spec, png);
}

} // namespace cementsph::study
