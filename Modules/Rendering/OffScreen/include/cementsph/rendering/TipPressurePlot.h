// The paper's Fig. 10 (Basafa et al. 2013): injection pressure at the cannula tip over time, from the CSV
// a simulation writes (header time_s,pressure_pa,pressure_minus_baseline_pa), drawn with XYPlot.
#pragma once

#include <filesystem>
#include <vector>

namespace cementsph::rendering {

struct TipPressureSeries {
  std::vector<double> timeS, pressurePa, pressureMinusBaselinePa;
  // Columns 4 and 5 when the header names them (cannula_pressure_drop_pa, injection_pressure_pa); else empty.
  std::vector<double> cannulaPa, injectionPa;
};

// Reads the CSV. The header must name the three columns in that order (extra columns after them are
// ignored); blank lines are skipped. Throws std::runtime_error (one line, naming the file and line) if
// the file cannot be read, the header is wrong, a value is not a finite number, or there are no rows.
TipPressureSeries readTipPressureCsv(const std::filesystem::path& csv);

struct TipPressurePlotOptions {
  // Plot pressure_minus_baseline_pa (the pressure the cement adds) instead of the absolute pressure.
  bool minusBaseline = false;
  int widthPx = 900, heightPx = 650;
};

// Writes the plot (time in s against pressure in kPa; kPa because injection pressures are 10^4..10^6 Pa
// and the axis labels stay short). Errors as readTipPressureCsv() and writePlotPng().
void writeTipPressurePlot(const std::filesystem::path& csv, const std::filesystem::path& png,
                          const TipPressurePlotOptions& options = {});
// The same from a series in memory (a run's own, so nothing re-reads the CSV it wrote); errors as writePlotPng().
void writeTipPressurePlot(const TipPressureSeries& series, const std::filesystem::path& png,
                          const TipPressurePlotOptions& options = {});

// The pressures a planner reads over time, in kPa: at the syringe (injection_pressure_pa), the cannula's
// drop and at the outlet (Fig. 10's curve). The CSV must have the two extra columns (std::runtime_error
// otherwise, naming the file).
void writeInjectionPressurePlot(const std::filesystem::path& csv, const std::filesystem::path& png,
                                const TipPressurePlotOptions& options = {});
// The same from a series in memory; std::runtime_error when it has no cannula and injection pressures.
void writeInjectionPressurePlot(const TipPressureSeries& series, const std::filesystem::path& png,
                                const TipPressurePlotOptions& options = {});

} // namespace cementsph::rendering
