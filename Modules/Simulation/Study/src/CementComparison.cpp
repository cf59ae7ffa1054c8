#include "cementsph/study/CementComparison.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/PolyDataIO.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/provenance/Provenance.h"
#include "cementsph/study/AlignedPost.h"

#include <itkIdentityTransform.h>

#include <chrono>
#include <filesystem>
#include <cmath>
#include <stdexcept>

namespace cementsph::study {

namespace {

namespace fs = std::filesystem;
namespace sm = cementsph::surfacemetrics;
using namespace cementsph::imaging;
using nlohmann::json;

double secondsSince(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

json cementJson(const AnalysedCement& c) {
  json j;
  j["cement_found"] = c.found();
  j["cement_volume_ml"] = c.segmentation.volumeMl;
  j["cement_voxels"] = c.segmentation.voxels;
  j["mean_spreading_distance_mm"] = c.spreadingMm;
  j["centroid_mm"] = c.found() ? json(c.centroid) : json(nullptr);
  j["threshold_rule"] = c.segmentation.thresholdRule;
  j["cement_threshold_hu"] = c.segmentation.thresholdHU;
  j["cement_contrast_hu"] = c.segmentation.thresholdRule == "fixed" ? json(nullptr) : json(c.segmentation.cementContrastHU);
  j["components_above_threshold"] = c.segmentation.componentsFound;
  j["component_selection"] = c.segmentation.selection;
  if (c.segmentation.selection == "nearest-to-injection-point")
    j["component_distance_to_injection_point_mm"] = c.segmentation.distanceToInjectionPointMm;
  j["surface_vertices"] = c.surface ? c.surface->GetNumberOfPoints() : 0;
  return j;
}

json directedJson(const sm::DirectedDistance& d) {
  return {{"vertices", d.vertices}, {"mean_mm", d.meanMm}, {"max_mm", d.maxMm},
          {"std_mm", d.stdMm},      {"p95_mm", d.p95Mm}};
}

json registrationJson(const RegistrationResult& registration) {
  json levels = json::array();
  for (const auto& l : registration.levels)
    levels.push_back({{"stage", l.stage}, {"level", l.level}, {"shrink_factor", l.shrink},
                      {"iterations", l.iterations}, {"metric_mean_squares_hu2", l.metric},
                      {"stop_condition", l.stopCondition}});
  return {{"method", "ITK v4: translation then affine, multi-resolution, mean squares, cement masked"},
          {"final_metric_mean_squares_hu2", registration.finalMetric},
          {"levels", levels},
          {"cement_mask_threshold_hu", registration.cementThresholdHU},
          {"cement_masked_moving_voxels", registration.maskedMovingVoxels},
          {"transform_file", "pre_to_post.tfm"},
          {"transform_maps", "points of the pre CT (mm) to the same points of the post CT; resampling the post CT "
                             "through it puts it on the pre CT's grid (registered_post.nrrd)"}};
}

PointType pointOf(const sm::Point3& p) {
  PointType point;
  for (unsigned i = 0; i < 3; ++i) point[i] = p[i];
  return point;
}

// 1. Read the volumes; the injection point must lie in the pre volume.
void readVolumes(const CementComparisonRequest& r, const sm::Point3& injection, CementComparison& c) {
  const auto t = std::chrono::steady_clock::now();
  c.pre = readVolume(r.pre);
  c.registered = readVolume(r.post); // registered in place by alignVolumes
  if (!r.simulated.empty()) {
    c.simulated = readVolume(r.simulated);
    const std::filesystem::path labels = std::filesystem::path(r.simulated).parent_path() / "cement_labels.nrrd";
    if (std::filesystem::exists(labels)) c.simulatedLabels = readVolume(labels.string());
  }
  ImageType::IndexType index;
  if (!c.pre->TransformPhysicalPointToIndex(pointOf(injection), index))
    throw std::runtime_error("the injection point (" + std::to_string(injection[0]) + ", " +
                             std::to_string(injection[1]) + ", " + std::to_string(injection[2]) +
                             ") mm lies outside the pre-injection volume");
  c.timingS["read_s"] = secondsSince(t);
}

// 2. Register post onto pre and resample it onto pre's grid; the simulated CT onto pre's grid too.
void alignVolumes(const CementComparisonRequest& r, CementComparison& c) {
  const auto t = std::chrono::steady_clock::now();
  RegistrationOptions registrationOptions;
  registrationOptions.maskCement = r.maskCement;
  AlignedPost aligned = alignPostOntoPre(c.pre, c.registered, r.registration, registrationOptions);
  c.registration = aligned.registration;
  c.registered = aligned.volume;
  c.timingS["registration_s"] = secondsSince(t);
  if (c.simulated && !geometryOf(c.simulated).sameGrid(geometryOf(c.pre))) {
    if (overlapVolumeMm3(geometryOf(c.pre), geometryOf(c.simulated)) <= 0.0)
      throw std::runtime_error("the simulated and pre volumes do not overlap in space");
    c.simulated = resampleOnto(c.simulated, c.pre, itk::IdentityTransform<double, 3>::New());
  }
}

SegmentationOptions segmentationOptions(const CementComparisonRequest& r, const sm::Point3& injection) {
  SegmentationOptions seg;
  if (r.thresholdHU) seg.differenceThresholdHU = *r.thresholdHU;
  seg.injectionPointMm = pointOf(injection);
  seg.injectionSearchRadiusMm = r.searchRadiusMm;
  seg.closingRadiusMm = r.closingMm;
  return seg;
}

json baseMetrics(const CementComparisonRequest& r, const SegmentationOptions& seg, const CementComparison& c) {
  json metrics;
  metrics["inputs"] = {{"pre", r.pre},
                       {"post", r.post},
                       {"simulated", r.simulated.empty() ? json(nullptr) : json(r.simulated)},
                       {"injection_point_mm", r.injectionMm}};
  metrics["segmentation"] = {{"threshold_rule", describeThresholdRule(seg)},
                             {"closing_radius_mm", r.closingMm},
                             {"injection_search_radius_mm", r.searchRadiusMm},
                             {"surface_smoothing_sigma_voxels", r.smoothingVoxels}};
  metrics["registration"] = c.registration ? registrationJson(*c.registration) : json(nullptr);
  metrics["cement_volume_ml"] = c.ct.segmentation.volumeMl;
  metrics["cement_threshold_hu"] = c.ct.segmentation.thresholdHU;
  metrics["mean_spreading_distance_mm"] = c.ct.spreadingMm;
  metrics["ct"] = cementJson(c.ct);
  return metrics;
}

// 4. The simulated CT against the CT: overlap, and surface distances when both have cement.
void compareWithSimulated(CementComparison& c) {
  const AnalysedCement& sim = *c.sim;
  json& metrics = c.metrics;
  metrics["simulated"] = cementJson(sim);
  if (!sim.found()) c.warnings.push_back("no cement found in the simulated CT");
  c.overlap = sm::overlap(c.ct.vtkMask, sim.vtkMask);
  metrics["dice"] = c.overlap->dice;
  metrics["jaccard"] = c.overlap->jaccard;
  metrics["simulated_minus_ct_volume_ml"] = sim.segmentation.volumeMl - c.ct.segmentation.volumeMl;
  if (!(c.ct.found() && sim.found())) {
    for (const char* key : {"error_mm", "hausdorff_mm", "hausdorff95_mm", "centroid_offset_mm"}) metrics[key] = nullptr;
    return;
  }
  const auto t = std::chrono::steady_clock::now();
  c.surfaces = sm::compareSurfaces(c.ct.surface, sim.surface);
  c.timingS["surface_metrics_s"] = secondsSince(t);
  metrics["ct_to_simulated_distance"] = directedJson(c.surfaces->aToB);
  metrics["simulated_to_ct_distance"] = directedJson(c.surfaces->bToA);
  metrics["error_mm"] = c.surfaces->errorMm;
  metrics["error_direction"] = c.surfaces->errorDirection == "a_to_b" ? "ct_to_simulated" : "simulated_to_ct";
  metrics["hausdorff_mm"] = c.surfaces->hausdorffMm;
  metrics["hausdorff95_mm"] = c.surfaces->hausdorff95Mm;
  sm::Point3 d;
  for (int i = 0; i < 3; ++i) d[i] = sim.centroid[i] - c.ct.centroid[i];
  metrics["centroid_offset_vector_mm"] = d;
  c.centroidOffsetMm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  metrics["centroid_offset_mm"] = *c.centroidOffsetMm;
}

} // namespace

CementComparison compareCement(const CementComparisonRequest& r) {
  if (r.injectionMm.size() != 3) throw std::invalid_argument("the injection point needs 3 coordinates (x, y, z), mm");
  const sm::Point3 injection{r.injectionMm[0], r.injectionMm[1], r.injectionMm[2]};
  CementComparison c;
  readVolumes(r, injection, c);
  alignVolumes(r, c);
  // 3. Segment and measure.
  const auto t = std::chrono::steady_clock::now();
  const SegmentationOptions seg = segmentationOptions(r, injection);
  c.ct = analyseCement(c.registered, c.pre, seg, injection, r.smoothingVoxels);
  if (c.simulated) c.sim = analyseCement(c.simulated, c.pre, seg, injection, r.smoothingVoxels);
  c.timingS["segmentation_s"] = secondsSince(t);
  c.metrics = baseMetrics(r, seg, c);
  // A comparison without cement in the post scan has nothing to compare: no output (issue "Trust, round
  // two", item 3), one line saying what to check.
  if (!c.ct.found())
    throw std::invalid_argument("--post " + r.post + ": no cement found in the post-injection CT at the injection "
                                "point (is it the pre scan again? check --post, --injection-point-mm, or give "
                                "--threshold-hu)");
  if (c.sim) compareWithSimulated(c);
  c.metrics["warnings"] = c.warnings;
  return c;
}

void writeCementComparison(CementComparison& c, const fs::path& out) {
  const auto t = std::chrono::steady_clock::now();
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw std::runtime_error(out.string() + ": cannot create output directory: " + ec.message());
  writeVolume(c.registered, (out / "registered_post.nrrd").string());
  if (c.registration) writeTransform(c.registration->transform, (out / "pre_to_post.tfm").string());
  writeMask(c.ct.segmentation.mask, (out / "cement_ct_mask.nrrd").string());
  if (c.ct.surface) writePolyData(c.ct.surface, (out / "cement_ct_surface.vtp").string());
  if (c.sim) {
    writeMask(c.sim->segmentation.mask, (out / "cement_simulated_mask.nrrd").string());
    if (c.sim->surface) writePolyData(c.sim->surface, (out / "cement_simulated_surface.vtp").string());
  }
  c.timingS["write_s"] = secondsSince(t);
  c.timingS["total_s"] = secondsSince(c.started);
  c.metrics["timing_s"] = c.timingS;
  c.metrics["provenance"] = provenance::toJson();
  writeCementComparisonMetrics(c, out);
}

void writeCementComparisonMetrics(const CementComparison& c, const fs::path& out) {
  writeTextAtomically((out / "metrics.json").string(), c.metrics.dump(2) + "\n");
}

} // namespace cementsph::study
