#include "cementsph/study/DemoReport.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/provenance/Provenance.h"

namespace cementsph::study {

namespace {

using nlohmann::json;

json orNull(const std::optional<double>& x) { return x ? json(*x) : json(nullptr); }

// An engine's own figure (InjectionResult::engineFigures), null when the engine has none of that name.
json engineFigure(const scene::InjectionRunResult& r, const char* key) {
  return r.engineFigures.contains(key) ? r.engineFigures.at(key) : json(nullptr);
}

json injectFigures(const scene::InjectionSummary& s) {
  return {{"volume_injected_ml", s.volumeInjectedMl},
          {"simulated_time_s", s.simulatedTimeS},
          {"wall_time_s", s.wallTimeS},
          {"real_time_factor", s.toJson().at("real_time_factor")}, // the summary's own definition
          {"max_tip_pressure_pa", s.maxTipPressurePa},
          {"mean_spreading_distance_mm", s.meanSpreadingDistanceMm}};
}

json compareFigures(const CementComparison& c) {
  const auto& surfaces = c.surfaces;
  return {{"error_mm", surfaces ? json(surfaces->errorMm) : json(nullptr)},
          {"hausdorff95_mm", surfaces ? json(surfaces->hausdorff95Mm) : json(nullptr)},
          {"dice", c.overlap ? json(c.overlap->dice) : json(nullptr)},
          {"jaccard", c.overlap ? json(c.overlap->jaccard) : json(nullptr)},
          {"cement_volume_ml", c.ct.segmentation.volumeMl}};
}

json xrayFigures(const drr::XrayHeadline& x) {
  return {{"final_time_s", x.finalTimeS},
          {"final_projected_area_mm2", x.finalProjectedAreaMm2},
          {"final_reference_projected_area_mm2", orNull(x.finalReferenceProjectedAreaMm2)},
          {"final_frame_dice", orNull(x.finalFrameDice)},
          {"final_frame_iou", orNull(x.finalFrameIou)}};
}

void writeJson(json metrics, const std::filesystem::path& file) {
  metrics["provenance"] = provenance::toJson();
  imaging::writeTextAtomically(file.string(), metrics.dump(2) + "\n");
}

} // namespace

json foamDemoMetricsJson(const FoamDemoResults& r) {
  return {{"inject", injectFigures(r.inject.summary)},
          {"compare", compareFigures(r.compare)},
          {"xray", xrayFigures(r.xray)},
          {"post_scan_made_by", "the model itself (pipeline check, not a validation)"},
          {"wall_time_s", r.wallTimeS}};
}

void writeFoamDemoMetrics(const FoamDemoResults& results, const std::filesystem::path& file) {
  writeJson(foamDemoMetricsJson(results), file);
}

json vertebraDemoMetricsJson(const scene::InjectionRunResult& inject, double wallTimeS) {
  const scene::InjectionSummary& s = inject.summary;
  return {{"bone_model", s.boneModel},
          {"bone_model_reason", s.boneModelReason},
          {"porosity_at_tip", engineFigure(inject, "porosity_at_tip")},
          {"permeability_at_tip_m2", engineFigure(inject, "permeability_at_tip_m2")},
          {"volume_injected_ml", s.volumeInjectedMl},
          {"cement_volume_ml", s.cementVolumeMl},
          {"mean_spreading_distance_mm", s.meanSpreadingDistanceMm},
          {"final_tip_pressure_pa", s.finalTipPressurePa},
          {"max_tip_pressure_pa", s.maxTipPressurePa},
          {"injection_pressure_pa", s.injectionPressurePa},
          {"leakage_volume_ml", s.leakageVolumeMl},
          {"leakage_sites", s.toJson().at("leakage_sites")}, // the summary's own site schema
          {"wall_time_s", wallTimeS}};
}

void writeVertebraDemoMetrics(const scene::InjectionRunResult& inject, double wallTimeS,
                              const std::filesystem::path& file) {
  writeJson(vertebraDemoMetricsJson(inject, wallTimeS), file);
}

} // namespace cementsph::study
