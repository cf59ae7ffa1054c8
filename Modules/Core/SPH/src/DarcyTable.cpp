#include "cementsph/sph/DarcyTable.h"

#include "cementsph/sph/Simulation.h"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace cementsph::sph {

std::string darcyPermeabilityCsv(const std::vector<DarcyResult>& results, const DarcyTableModel& model) {
  std::ostringstream csv;
  csv << "porosity,spacing_mm,viscosity_pa_s,slope_s,r2,permeability_m2,dimensionless_permeability,"
         "kozeny_carman_dimensionless,steps,wall_s,converged,intercept_m_per_s,h_over_d,drag_coefficient,integrator\n";
  csv << std::setprecision(8);
  for (const DarcyResult& r : results) {
    for (double x : {r.slope, r.r2, r.permeability, r.dimensionlessPermeability, r.intercept,
                     kozenyCarmanDimensionless(r.porosity)})
      if (!std::isfinite(x))
        throw SimulationError("the Darcy case at porosity " + std::to_string(r.porosity) + " gave a non-finite fit (" +
                              std::to_string(x) + "); nothing written for it");
    csv << r.porosity << ',' << r.input.spacing * 1e3 << ',' << r.input.viscosity << ',' << r.slope << ',' << r.r2
        << ',' << r.permeability << ',' << r.dimensionlessPermeability << ',' << kozenyCarmanDimensionless(r.porosity)
        << ',' << r.steps << ',' << r.wallSeconds << ',' << (r.converged ? 1 : 0) << ',' << r.intercept << ','
        << model.hOverD << ',' << model.dragCoefficient << ',' << model.integrator << '\n';
  }
  return csv.str();
}

} // namespace cementsph::sph
