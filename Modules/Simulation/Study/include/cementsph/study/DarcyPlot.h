// The Darcy benchmark's picture (`cementsph darcy`, paper Fig. 5): dimensionless permeability k/d^2 against
// porosity, one series per particle spacing and viscosity (Darcy's law says they fall on one curve), with the
// Kozeny-Carman curve over the same porosities. Beside the study's other plots (StudyPlots.h).
#pragma once

#include "cementsph/sph/DarcyBenchmark.h"

#include <filesystem>
#include <vector>

namespace cementsph::study {

// Writes png; throws std::runtime_error naming it when no result has a positive permeability (a log axis).
void writeDarcyPlot(const std::vector<sph::DarcyResult>& results, const std::filesystem::path& png);

} // namespace cementsph::study
