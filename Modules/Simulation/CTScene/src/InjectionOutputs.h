// Pieces of an injection's output that both runners write the same way (InjectionRunner.h): the ParaView
// series of the snapshots and the outlet-pressure table.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace cementsph::scene::detail {

// One row of tip_pressure.csv: the outlet pressure and the cannula's drop at a time [s, Pa, Pa].
struct TipRecord {
  double time, tipPa, cannulaPa;
};

// particles.pvd: (time [s], file name) of each snapshot.
std::string particleCollection(const std::vector<std::pair<double, std::string>>& snapshots);

// tip_pressure.csv. `baselinePa` is subtracted in pressure_minus_baseline_pa (0 where the pressure is physical);
// none (a model pressure whose baseline is not known yet): that column is 0.
std::string tipPressureCsv(const std::vector<TipRecord>& series, std::optional<double> baselinePa);

} // namespace cementsph::scene::detail
