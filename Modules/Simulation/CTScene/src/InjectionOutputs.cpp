#include "InjectionOutputs.h"

#include <iomanip>
#include <sstream>

namespace cementsph::scene::detail {

std::string particleCollection(const std::vector<std::pair<double, std::string>>& snapshots) {
  std::ostringstream pvd;
  pvd << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (const auto& [t, name] : snapshots)
    pvd << "    <DataSet timestep=\"" << std::setprecision(10) << t << "\" part=\"0\" file=\"" << name << "\"/>\n";
  pvd << "  </Collection>\n</VTKFile>\n";
  return pvd.str();
}

std::string tipPressureCsv(const std::vector<TipRecord>& series, std::optional<double> baselinePa) {
  std::ostringstream csv;
  csv << "time_s,pressure_pa,pressure_minus_baseline_pa,cannula_pressure_drop_pa,injection_pressure_pa\n"
      << std::setprecision(10);
  for (const auto& s : series)
    csv << s.time << "," << s.tipPa << "," << (baselinePa ? s.tipPa - *baselinePa : 0.0) << "," << s.cannulaPa << "," << s.tipPa + s.cannulaPa
        << "\n";
  return csv.str();
}

} // namespace cementsph::scene::detail
