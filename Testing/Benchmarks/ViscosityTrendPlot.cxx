// viscosity-trend-plot: the figure of VALIDATION.md "The viscosity trend, honestly" (issue 9 item 5, issue 19
// item 4, issue 20 item 2) from its table, docs/validation/viscosity-trend.csv, one row per viscosity:
//   viscosity_pa_s, then the mean spreading on the foam phantom, 5 ml, per model (equation of state, voxel-darcy,
//   voxel-darcy + capillary entry at 0.025 N/m) [mm], then the leak volume on the vertebra phantom with a vein,
//   3 ml (voxel-darcy single phase, + capillary entry at 0.025 N/m, at 0.1 N/m) [ml].
// Two panels side by side: left the spreading with the paper's 7-9 mm range and the interval (100 to 200 Pa.s) over
// which the paper saw it drop; right the leak volume, the mechanism's answer to "higher viscosity cuts leakage".
// Usage: viscosity-trend-plot CSV PNG.
#include "cementsph/rendering/XYPlot.h"

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace {

constexpr std::size_t kColumns = 7;

using cementsph::rendering::PlotSeries;
using Rgb = std::array<unsigned char, 3>;

PlotSeries series(std::string name, std::vector<double> x, std::vector<double> y, PlotSeries::Style style,
                  std::array<unsigned char, 3> rgb, double width) {
  PlotSeries p;
  p.name = std::move(name), p.x = std::move(x), p.y = std::move(y), p.style = style, p.rgb = rgb, p.width = width;
  return p;
}

// The two panels, one beside the other, as one RGB picture (a panel's alpha, if any, is dropped).
void besideEachOther(const std::filesystem::path& left, const std::filesystem::path& right,
                     const std::filesystem::path& out) {
  vtkNew<vtkPNGReader> readers[2];
  int width[2] = {0, 0}, height = 0;
  for (int i = 0; i < 2; ++i) {
    readers[i]->SetFileName((i == 0 ? left : right).string().c_str());
    readers[i]->Update();
    int dims[3];
    readers[i]->GetOutput()->GetDimensions(dims);
    if (readers[i]->GetErrorCode() != 0 || readers[i]->GetOutput()->GetPointData()->GetScalars() == nullptr)
      throw std::runtime_error("cannot read the panel just written");
    width[i] = dims[0];
    if (i == 1 && dims[1] != height) throw std::runtime_error("the panels differ in height");
    height = dims[1];
  }
  vtkNew<vtkImageData> image;
  image->SetDimensions(width[0] + width[1], height, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* to = static_cast<unsigned char*>(image->GetScalarPointer());
  for (int i = 0; i < 2; ++i) {
    vtkDataArray* from = readers[i]->GetOutput()->GetPointData()->GetScalars();
    const int components = from->GetNumberOfComponents();
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width[i]; ++x)
        for (int c = 0; c < 3; ++c)
          to[3 * (std::size_t(y) * std::size_t(width[0] + width[1]) + std::size_t(x + (i == 1 ? width[0] : 0))) +
             std::size_t(c)] = static_cast<unsigned char>(
              from->GetComponent(vtkIdType(y) * width[i] + x, components >= 3 ? c : 0));
  }
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(out.string().c_str());
  writer->SetInputData(image);
  writer->Write();
  if (writer->GetErrorCode() != 0) throw std::runtime_error("cannot write " + out.string());
}

} // namespace

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
  std::vector<std::vector<double>> columns(kColumns);
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string cell;
    for (auto& c : columns) {
      if (!std::getline(s, cell, ',')) {
        std::cerr << "viscosity-trend-plot: " << argv[1] << ": a row has fewer than " << kColumns
                  << " columns (viscosity, three spreadings in mm, three leak volumes in ml)\n";
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
  if (columns[0].size() < 2) {
    std::cerr << "viscosity-trend-plot: " << argv[1] << ": needs at least two viscosities\n";
    return 1;
  }
  const auto both = PlotSeries::Style::LineAndPoints, lineOnly = PlotSeries::Style::Line;
  const std::vector<double>& mu = columns[0];
  const std::vector<double> ends{mu.front(), mu.back()};

  // A panel against the viscosity (log axis) with its y range.
  auto panel = [](std::string title, std::string yLabel, double yMin, double yMax) {
    cementsph::rendering::PlotSpec p;
    p.title = std::move(title), p.xLabel = "cement viscosity (Pa.s)", p.yLabel = std::move(yLabel);
    p.logX = true, p.yMin = yMin, p.yMax = yMax;
    return p;
  };
  // Each table column as a series against the viscosity: its legend, column, colour.
  auto add = [&](cementsph::rendering::PlotSpec& p, std::vector<std::tuple<std::string, int, Rgb>> rows) {
    for (auto& [name, column, rgb] : rows)
      p.series.push_back(series(name, mu, columns[std::size_t(column)], both, rgb, 2.0));
  };
  auto spreading = panel("Spreading against viscosity, foam phantom, 5 ml at 0.05 ml/s", "mean spreading distance (mm)",
                         6.5, 11.0);
  add(spreading, {{"equation of state (paper's model)", 1, {214, 39, 40}},
                  {"voxel-darcy (default)", 2, {31, 119, 180}},
                  {"voxel-darcy + capillary entry, 0.025 N/m", 3, {44, 160, 44}}});
  spreading.series.push_back(series("paper's range, 9 mm", ends, {9.0, 9.0}, lineOnly, {150, 150, 150}, 1.0));
  spreading.series.push_back(series("paper's range, 7 mm", ends, {7.0, 7.0}, lineOnly, {150, 150, 150}, 1.0));
  // The paper reports a drop between 100 and 200 Pa.s within its range, not the values: a bracket marks the interval.
  spreading.series.push_back(series("paper: spreading drops from 100 to 200 Pa.s", {100.0, 100.0, 200.0, 200.0},
                                    {7.0, 9.0, 9.0, 7.0}, lineOnly, {0, 0, 0}, 1.5));
  auto leak = panel("Leakage against viscosity, vertebra phantom with a vein, 3 ml", "leaked volume (ml)", 0.0, 0.1);
  add(leak, {{"voxel-darcy, single phase (default)", 4, {31, 119, 180}},
             {"+ capillary entry, 0.025 N/m", 5, {44, 160, 44}},
             {"+ capillary entry, 0.1 N/m", 6, {148, 103, 189}}});

  const std::filesystem::path out(argv[2]);
  const std::filesystem::path left = out.string() + ".left.png", right = out.string() + ".right.png";
  int status = 0;
  try {
    cementsph::rendering::writePlotPng(spreading, left);
    cementsph::rendering::writePlotPng(leak, right);
    besideEachOther(left, right, out);
  } catch (const std::exception& e) {
    std::cerr << "viscosity-trend-plot: " << e.what() << "\n";
    status = 1;
  }
  std::error_code ignored;
  std::filesystem::remove(left, ignored);
  std::filesystem::remove(right, ignored);
  return status;
}
