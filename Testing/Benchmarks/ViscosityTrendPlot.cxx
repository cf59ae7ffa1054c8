// viscosity-trend-plot: the figure of VALIDATION.md "The viscosity trend, honestly" (issue 9, item 5) from its
// table, docs/validation/viscosity-trend.csv (mean spreading on the phantom, 5 ml, per model), with the
// paper's 7-9 mm range beside it. Usage: viscosity-trend-plot CSV PNG.
#include "cementsph/rendering/XYPlot.h"

#include <array>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: viscosity-trend-plot docs/validation/viscosity-trend.csv OUT.png\n";
    return 1;
  }
  std::ifstream in(argv[1]);
  std::string line;
  if (!in || !std::getline(in, line)) {
    std::cerr << "viscosity-trend-plot: " << argv[1] << ": cannot read\n";
    return 1;
  }
  std::vector<std::vector<double>> columns(4);
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string cell;
    for (auto& c : columns) {
      if (!std::getline(s, cell, ',')) {
        std::cerr << "viscosity-trend-plot: " << argv[1] << ": a row has fewer than 4 columns\n";
        return 1;
      }
      std::size_t used = 0;
      double v = 0;
      try {
        v = std::stod(cell, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || !std::isfinite(v)) {
        std::cerr << "viscosity-trend-plot: " << argv[1] << ": \"" << cell << "\" is not a number\n";
        return 1;
      }
      c.push_back(v);
    }
  }
  using cementsph::rendering::PlotSeries;
  cementsph::rendering::PlotSpec spec;
  spec.title = "Spreading against viscosity, phantom, 5 ml at 0.05 ml/s";
  spec.xLabel = "cement viscosity (Pa.s)";
  spec.yLabel = "mean spreading distance (mm)";
  spec.logX = true;
  spec.yMin = 6.5, spec.yMax = 11.0;
  const std::vector<double>& mu = columns[0];
  auto series = [](std::string name, std::vector<double> x, std::vector<double> y, PlotSeries::Style style,
                   std::array<unsigned char, 3> rgb, double width) {
    PlotSeries p;
    p.name = std::move(name), p.x = std::move(x), p.y = std::move(y), p.style = style, p.rgb = rgb, p.width = width;
    return p;
  };
  const auto both = PlotSeries::Style::LineAndPoints, lineOnly = PlotSeries::Style::Line;
  spec.series.push_back(series("equation of state (paper's model)", mu, columns[1], both, {214, 39, 40}, 2.0));
  spec.series.push_back(series("voxel-darcy (default)", mu, columns[2], both, {31, 119, 180}, 2.0));
  spec.series.push_back(series("voxel-darcy + capillary entry", mu, columns[3], both, {44, 160, 44}, 2.0));
  const std::vector<double> ends{mu.front(), mu.back()};
  spec.series.push_back(series("paper's range, 9 mm", ends, {9.0, 9.0}, lineOnly, {150, 150, 150}, 1.0));
  spec.series.push_back(series("paper's range, 7 mm", ends, {7.0, 7.0}, lineOnly, {150, 150, 150}, 1.0));
  try {
    cementsph::rendering::writePlotPng(spec, argv[2]);
  } catch (const std::exception& e) {
    std::cerr << "viscosity-trend-plot: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
