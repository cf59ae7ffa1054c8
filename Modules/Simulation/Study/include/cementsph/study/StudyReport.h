// The study's tables: CSV (every figure, machine-readable, columns named with their units) and Markdown
// (the figures a reader compares: speed against error, the paper's Fig. 6 as a table). A figure that could
// not be computed (a failed run, no cement found) is an empty CSV field and "n/a" in Markdown, never NaN.
#pragma once

#include "cementsph/study/StudyRow.h"

#include <string>
#include <vector>

namespace cementsph::study {

// study.csv: one row per size-study run, in run order. Columns: run, integrator, particle_radius_mm,
// reference, status, wall_time_s, real_time_factor, steps, fluid_particles, expected_fluid_particles,
// fixed_particles, escaped_particles, volume_injected_ml, simulated_time_s, particle_spreading_distance_mm,
// cement_volume_ml, cement_spreading_distance_mm, surface_error_mm, hausdorff95_mm, dice,
// spreading_difference_mm, max_tip_pressure_pa, fluid_in_solid_fraction, analysis_time_s, failure, rank.
std::string sizeStudyCsv(const std::vector<StudyRow>& rows);

// spreading_vs_viscosity.csv: one row per viscosity. Columns: viscosity_pa_s, particle_radius_mm,
// integrator, status, particle_spreading_distance_mm, cement_spreading_distance_mm, cement_volume_ml,
// max_tip_pressure_pa, steps, wall_time_s, real_time_factor, fluid_particles, fixed_particles,
// escaped_particles, fluid_in_solid_fraction, failure, rank.
std::string viscosityCsv(const std::vector<StudyRow>& rows);

// A Markdown table of the size study (one row per run, the reference marked) and, when given, of the
// viscosity sweep, under a title and the caller's lines about the inputs (each a paragraph line).
std::string studyMarkdown(const std::vector<StudyRow>& sizeRows, const std::vector<StudyRow>& viscosityRows,
                          const std::vector<std::string>& preamble);

// "1.00" for radii (two decimals, as the paper writes them).
std::string radiusLabel(double radiusMm);

} // namespace cementsph::study
