// Line and scatter plots written straight to PNG, drawn with VTK's 2-D charts (vtkChartXY).
// No display needed: writePlotPng() arranges one itself (VirtualDisplay).
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cementsph::rendering {

struct PlotSeries {
  std::string name; // legend entry (the legend is shown when a plot has more than one series)
  std::vector<double> x, y;
  enum class Style { Line, Points, LineAndPoints } style = Style::LineAndPoints;
  std::array<unsigned char, 3> rgb{31, 119, 180};
  double width = 2.0; // line width in pixels; also scales the markers
  // Optional text beside each point (empty: none; else one per point, "" for an unlabelled point), drawn in
  // the series' colour just right of and above the point, e.g. the particle radius of each run of a study.
  std::vector<std::string> pointLabels;
};

struct PlotSpec {
  std::string title, xLabel, yLabel;
  bool logX = false, logY = false;
  int widthPx = 900, heightPx = 650;
  std::vector<PlotSeries> series;
  // Axis limits; any left empty come from the data.
  std::optional<double> xMin, xMax, yMin, yMax;
};

// Throws std::invalid_argument (one line naming the series and the fault) for: no series, a series with
// no points, x/y of different lengths, point labels not one per point, non-finite values, values <= 0 on
// a log axis, bad limits, bad width/size. Throws std::runtime_error if rendering or writing fails. Either way no file is left behind.
void writePlotPng(const PlotSpec& spec, const std::filesystem::path& png);

// The validation writePlotPng() performs, for callers that want to check a spec before doing other work.
void validatePlotSpec(const PlotSpec& spec);

} // namespace cementsph::rendering
