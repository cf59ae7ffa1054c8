// Fig. 10 style tip-pressure plots: a thin CSV reader in front of writePlotPng(), so the axis titles
// always carry the units and a malformed file is reported with its line instead of a wrong picture.
#include "cementsph/rendering/TipPressurePlot.h"

#include "cementsph/rendering/XYPlot.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace cementsph::rendering {

namespace {

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream ss(line);
  std::string f;
  while (std::getline(ss, f, ',')) {
    const auto b = f.find_first_not_of(" \t\r");
    const auto e = f.find_last_not_of(" \t\r");
    fields.push_back(b == std::string::npos ? std::string() : f.substr(b, e - b + 1));
  }
  return fields;
}

} // namespace

TipPressureSeries readTipPressureCsv(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  if (!in) throw std::runtime_error("cannot read " + csv.string());
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(csv.string() + ": empty file");
  const auto header = splitCsv(line);
  if (header.size() < 3 || header[0] != "time_s" || header[1] != "pressure_pa" ||
      header[2] != "pressure_minus_baseline_pa")
    throw std::runtime_error(csv.string() + ": header must be time_s,pressure_pa,pressure_minus_baseline_pa");
  TipPressureSeries s;
  const bool pressures = header.size() >= 5 && header[3] == "cannula_pressure_drop_pa" &&
                         header[4] == "injection_pressure_pa";
  const int columns = pressures ? 5 : 3;
  int lineNo = 1;
  while (std::getline(in, line)) {
    ++lineNo;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto fields = splitCsv(line);
    if (int(fields.size()) < columns)
      throw std::runtime_error(csv.string() + ":" + std::to_string(lineNo) + ": fewer than " + std::to_string(columns) +
                               " values");
    double v[5];
    for (int i = 0; i < columns; ++i) {
      char* end = nullptr;
      v[i] = std::strtod(fields[i].c_str(), &end);
      if (fields[i].empty() || end == nullptr || *end != '\0' || !std::isfinite(v[i]))
        throw std::runtime_error(csv.string() + ":" + std::to_string(lineNo) + ": '" + fields[i] +
                                 "' is not a finite number");
    }
    s.timeS.push_back(v[0]);
    s.pressurePa.push_back(v[1]);
    s.pressureMinusBaselinePa.push_back(v[2]);
    if (pressures) {
      s.cannulaPa.push_back(v[3]);
      s.injectionPa.push_back(v[4]);
    }
  }
  if (s.timeS.empty()) throw std::runtime_error(csv.string() + ": no data rows");
  return s;
}

void writeTipPressurePlot(const std::filesystem::path& csv, const std::filesystem::path& png,
                          const TipPressurePlotOptions& options) {
  writeTipPressurePlot(readTipPressureCsv(csv), png, options);
}

void writeTipPressurePlot(const TipPressureSeries& data, const std::filesystem::path& png,
                          const TipPressurePlotOptions& options) {
  PlotSpec spec;
  spec.title = options.minusBaseline ? "Tip pressure above baseline" : "Injection pressure at the cannula tip";
  spec.xLabel = "time (s)";
  spec.yLabel = options.minusBaseline ? "pressure - baseline (kPa)" : "pressure (kPa)";
  spec.widthPx = options.widthPx;
  spec.heightPx = options.heightPx;
  PlotSeries series;
  series.name = "simulation";
  series.style = PlotSeries::Style::Line;
  series.x = data.timeS;
  const auto& pa = options.minusBaseline ? data.pressureMinusBaselinePa : data.pressurePa;
  for (double p : pa) series.y.push_back(p / 1000.0);
  spec.series = {series};
  writePlotPng(spec, png);
}

void writeInjectionPressurePlot(const std::filesystem::path& csv, const std::filesystem::path& png,
                                const TipPressurePlotOptions& options) {
  const TipPressureSeries data = readTipPressureCsv(csv);
  if (data.injectionPa.empty())
    throw std::runtime_error(csv.string() + ": no cannula_pressure_drop_pa and injection_pressure_pa columns");
  writeInjectionPressurePlot(data, png, options);
}

void writeInjectionPressurePlot(const TipPressureSeries& data, const std::filesystem::path& png,
                                const TipPressurePlotOptions& options) {
  if (data.injectionPa.size() != data.timeS.size() || data.cannulaPa.size() != data.timeS.size())
    throw std::runtime_error(png.string() + ": the series has no cannula and injection pressure for every time");
  PlotSpec spec;
  spec.title = "Injection pressure: syringe, cannula and outlet";
  spec.xLabel = "time (s)";
  spec.yLabel = "pressure (kPa)";
  spec.widthPx = options.widthPx;
  spec.heightPx = options.heightPx;
  auto curve = [&](const char* name, const std::vector<double>& pa, std::array<unsigned char, 3> rgb) {
    PlotSeries series;
    series.name = name;
    series.rgb = rgb;
    series.style = PlotSeries::Style::Line;
    series.x = data.timeS;
    for (double p : pa) series.y.push_back(p / 1000.0);
    return series;
  };
  spec.series = {curve("syringe (cannula + outlet)", data.injectionPa, {31, 119, 180}),
                 curve("cannula drop", data.cannulaPa, {255, 127, 14}), curve("outlet (tip)", data.pressurePa, {44, 160, 44})};
  writePlotPng(spec, png);
}

} // namespace cementsph::rendering
