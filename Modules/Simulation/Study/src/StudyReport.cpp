#include "cementsph/study/StudyReport.h"

#include "cementsph/study/StudyPlots.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>

namespace cementsph::study {

namespace {

// A CSV number: shortest form that reads back to the same double (17 significant digits at most);
// empty when absent or not finite (not computable), never "nan".
std::string num(std::optional<double> x) {
  if (!x || !std::isfinite(*x)) return "";
  char buf[40];
  for (int precision = 6; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, *x);
    if (std::strtod(buf, nullptr) == *x) break;
  }
  return buf;
}

// A Markdown figure with fixed decimals, "n/a" when absent.
std::string fixed(std::optional<double> x, int decimals) {
  if (!x || !std::isfinite(*x)) return "n/a";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, *x);
  return buf;
}

std::string signedFixed(std::optional<double> x, int decimals) {
  if (!x || !std::isfinite(*x)) return "n/a";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%+.*f", decimals, *x);
  return buf;
}

// Two or three significant figures for times and factors that span decades.
std::string sig(double x) {
  if (!std::isfinite(x)) return "n/a";
  char buf[40];
  std::snprintf(buf, sizeof buf, x >= 100 ? "%.0f" : x >= 10 ? "%.1f" : x >= 1 ? "%.2f" : "%.3f", x);
  return buf;
}

// One CSV text field: quoted, quotes doubled, line breaks folded into spaces.
std::string text(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += "\"\"";
    else if (c == '\n' || c == '\r') out += ' ';
    else out += c;
  }
  return out + "\"";
}

template <typename T> std::optional<double> okValue(const StudyRow& r, T value) {
  return r.ok() ? std::optional<double>(double(value)) : std::nullopt;
}

std::optional<double> cementValue(const StudyRow& r, double value) {
  return r.ok() && r.cementFound ? std::optional<double>(value) : std::nullopt;
}

} // namespace

std::string radiusLabel(double radiusMm) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", radiusMm);
  return buf;
}

std::string sizeStudyCsv(const std::vector<StudyRow>& rows) {
  std::ostringstream csv;
  csv << "run,integrator,particle_radius_mm,reference,status,wall_time_s,real_time_factor,steps,fluid_particles,"
         "expected_fluid_particles,fixed_particles,escaped_particles,volume_injected_ml,simulated_time_s,"
         "particle_spreading_distance_mm,cement_volume_ml,cement_spreading_distance_mm,surface_error_mm,"
         "hausdorff95_mm,dice,spreading_difference_mm,max_tip_pressure_pa,fluid_in_solid_fraction,analysis_time_s,"
         "failure,rank\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const StudyRow& r = rows[i];
    csv << i + 1 << ',' << r.spec.integrator << ',' << num(r.spec.particleRadiusMm) << ',' << (r.spec.reference ? 1 : 0)
        << ',' << (r.ok() ? "ok" : "failed") << ',' << num(okValue(r, r.wallTimeS)) << ','
        << num(okValue(r, r.realTimeFactor)) << ',' << num(okValue(r, r.steps)) << ','
        << num(okValue(r, r.fluidParticles)) << ',' << num(r.expectedParticles) << ','
        << num(okValue(r, r.fixedParticles)) << ',' << num(okValue(r, r.escapedParticles)) << ','
        << num(okValue(r, r.volumeInjectedMl)) << ',' << num(okValue(r, r.simulatedTimeS)) << ','
        << num(okValue(r, r.particleSpreadingMm)) << ',' << num(okValue(r, r.cementVolumeMl)) << ','
        << num(cementValue(r, r.cementSpreadingMm)) << ',' << num(r.errors.surfaceErrorMm) << ','
        << num(r.errors.hausdorff95Mm) << ',' << num(r.errors.dice) << ',' << num(r.errors.spreadingDifferenceMm)
        << ',' << num(okValue(r, r.maxTipPressurePa)) << ',' << num(okValue(r, r.fluidInSolidFraction)) << ','
        << num(okValue(r, r.analysisTimeS)) << ',' << text(r.failure) << ',' << r.rank << '\n';
  }
  return csv.str();
}

std::string viscosityCsv(const std::vector<StudyRow>& rows) {
  std::ostringstream csv;
  csv << "viscosity_pa_s,particle_radius_mm,integrator,status,particle_spreading_distance_mm,"
         "cement_spreading_distance_mm,cement_volume_ml,max_tip_pressure_pa,steps,wall_time_s,real_time_factor,"
         "fluid_particles,fixed_particles,escaped_particles,fluid_in_solid_fraction,failure,rank,"
         "final_tip_pressure_pa\n";
  for (const StudyRow& r : rows) {
    csv << num(r.spec.viscosityPaS) << ',' << num(r.spec.particleRadiusMm) << ',' << r.spec.integrator << ','
        << (r.ok() ? "ok" : "failed") << ',' << num(okValue(r, r.particleSpreadingMm)) << ','
        << num(cementValue(r, r.cementSpreadingMm)) << ',' << num(okValue(r, r.cementVolumeMl)) << ','
        << num(okValue(r, r.maxTipPressurePa)) << ',' << num(okValue(r, r.steps)) << ','
        << num(okValue(r, r.wallTimeS)) << ',' << num(okValue(r, r.realTimeFactor)) << ','
        << num(okValue(r, r.fluidParticles)) << ',' << num(okValue(r, r.fixedParticles)) << ','
        << num(okValue(r, r.escapedParticles)) << ',' << num(okValue(r, r.fluidInSolidFraction)) << ','
        << text(r.failure) << ',' << r.rank << ',' << num(okValue(r, r.finalTipPressurePa)) << '\n';
  }
  return csv.str();
}

std::string studyMarkdown(const std::vector<StudyRow>& sizeRows, const std::vector<StudyRow>& viscosityRows,
                          const std::vector<std::string>& preamble) {
  std::ostringstream md;
  md << "# CementSPH study: speed against error\n\n";
  for (const std::string& line : preamble) md << line << "\n";
  if (!preamble.empty()) md << "\n";
  std::vector<std::string> failures;
  auto failed = [&failures](const StudyRow& r, const std::string& what) {
    failures.push_back(what + ": " + r.failure);
    return "failed (" + std::to_string(failures.size()) + ")";
  };
  if (!sizeRows.empty()) {
    md << "## Particle size (paper Fig. 6)\n\n"
          "| integrator | r (mm) | fluid particles | fixed particles | steps | wall (s) | real-time factor | "
          "cement spreading (mm) | surface error (mm) | spreading diff. (mm) | Dice |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const StudyRow& r : sizeRows) {
      md << "| " << r.spec.integrator << (r.spec.reference ? " (reference)" : "") << " | "
         << radiusLabel(r.spec.particleRadiusMm) << " | ";
      if (!r.ok()) {
        md << failed(r, r.spec.name()) << " | | | | | | | | |\n";
        continue;
      }
      md << r.fluidParticles << " | " << r.fixedParticles << " | " << r.steps << " | " << sig(r.wallTimeS) << " | "
         << sig(r.realTimeFactor) << " | " << fixed(cementValue(r, r.cementSpreadingMm), 2) << " | "
         << fixed(r.errors.surfaceErrorMm, 3) << " | " << signedFixed(r.errors.spreadingDifferenceMm, 3) << " | "
         << fixed(r.errors.dice, 3) << " |\n";
    }
    md << "\n";
  }
  if (!viscosityRows.empty()) {
    md << "## Spreading against viscosity (paper Fig. 8)\n\n"
          "| viscosity (Pa.s) | r (mm) | integrator | spreading, particles (mm) | spreading, simulated CT (mm) | "
          "cement volume (ml) | max tip pressure (kPa) | steps | wall (s) |\n"
          "|---|---|---|---|---|---|---|---|---|\n";
    for (const StudyRow& r : viscosityRows) {
      md << "| " << num(r.spec.viscosityPaS) << " | " << radiusLabel(r.spec.particleRadiusMm) << " | "
         << r.spec.integrator << " | ";
      if (!r.ok()) {
        md << failed(r, r.spec.name()) << " | | | | | |\n";
        continue;
      }
      md << fixed(r.particleSpreadingMm, 2) << " | " << fixed(cementValue(r, r.cementSpreadingMm), 2) << " | "
         << fixed(r.cementVolumeMl, 3) << " | " << fixed(r.maxTipPressurePa / 1000.0, 2) << " | " << r.steps
         << " | " << sig(r.wallTimeS) << " |\n";
    }
    md << "\n";
    md << "## Outlet pressure at the end of injection against viscosity (paper Fig. 9)\n\n"
          "end_pressure_vs_viscosity.png: " << endPressureCaption() << "\n\n";
  }
  for (std::size_t i = 0; i < failures.size(); ++i) md << "(" << i + 1 << ") " << failures[i] << "\n";
  return md.str();
}

} // namespace cementsph::study
