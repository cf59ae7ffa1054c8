// The Darcy benchmark's table (`cementsph darcy`: permeability.csv): one row per case, its fit, the
// Kozeny-Carman value at its porosity and the model settings it ran with. Here, beside DarcyBenchmark.h, so
// that the command holds no schema.
#pragma once

#include "cementsph/sph/DarcyBenchmark.h"

#include <string>
#include <vector>

namespace cementsph::sph {

// The model settings every row records.
struct DarcyTableModel {
  double hOverD = 0.0;
  double dragCoefficient = 0.0;
  std::string integrator;
};

// The CSV text (header and one row per result, 8 significant digits). A result whose fit is not finite is a
// failed run: throws SimulationError naming its porosity, so the table never holds a NaN or infinity.
std::string darcyPermeabilityCsv(const std::vector<DarcyResult>& results, const DarcyTableModel& model);

} // namespace cementsph::sph
