// The report of `cementsph demo` (DIR/metrics.json): the headline figures of its steps, taken from each step's
// typed result (the inject run's, the comparison's, the X-ray sequence's), with the program's provenance. The
// schema lives here, beside the comparison it mostly reports, so the command only runs the steps and prints.
#pragma once

// ITK's headers (the comparison's) before the injection's: ITK carries its own copy of Eigen, which must come first.
#include "cementsph/study/CementComparison.h"

#include "cementsph/drr/XraySequenceFiles.h"
#include "cementsph/scene/InjectionRunner.h"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace cementsph::study {

// The foam demo: inject -> compare -> xray. Its post scan was made by the model itself (cementsph phantom), so
// the report says the comparison is a pipeline check, not a validation (post_scan_made_by).
struct FoamDemoResults {
  scene::InjectionRunResult inject;
  CementComparison compare;
  drr::XrayHeadline xray;
  double wallTimeS = 0; // the whole demo
};

// metrics.json: {"inject": {volume_injected_ml, simulated_time_s, wall_time_s, real_time_factor,
// max_tip_pressure_pa, mean_spreading_distance_mm}, "compare": {error_mm, hausdorff95_mm, dice, jaccard,
// cement_volume_ml}, "xray": {final_time_s, final_projected_area_mm2, final_reference_projected_area_mm2,
// final_frame_dice, final_frame_iou}, post_scan_made_by, wall_time_s, provenance}; a figure the step did not
// compute (no surfaces, no matched final frame) is null.
nlohmann::json foamDemoMetricsJson(const FoamDemoResults& results);
void writeFoamDemoMetrics(const FoamDemoResults& results, const std::filesystem::path& file);

// demo --vertebra: one injection into the clinical vertebra phantom with the continuum bone model.
// metrics.json: bone_model, bone_model_reason, porosity_at_tip, permeability_at_tip_m2 (the continuum model's,
// null for another), volume_injected_ml, cement_volume_ml, mean_spreading_distance_mm, final_tip_pressure_pa,
// max_tip_pressure_pa, injection_pressure_pa, leakage_volume_ml, leakage_sites, wall_time_s (the whole demo),
// provenance.
nlohmann::json vertebraDemoMetricsJson(const scene::InjectionRunResult& inject, double wallTimeS);
void writeVertebraDemoMetrics(const scene::InjectionRunResult& inject, double wallTimeS,
                              const std::filesystem::path& file);

} // namespace cementsph::study
