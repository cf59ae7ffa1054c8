// Output helpers shared by subcommands: every file is written to a temporary name in its folder
// and renamed into place, so a failure never leaves a partial file behind.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace cementsph::sph {
struct DarcyResult;
}

namespace cementsph::app {

void writeFileAtomically(const std::filesystem::path& path, const std::string& contents);
// Dimensionless permeability against porosity with the Kozeny-Carman curve (paper Fig. 5).
void writeDarcyPlot(const std::vector<sph::DarcyResult>& results, const std::filesystem::path& png);

} // namespace cementsph::app
