// The comparison `cementsph compare` makes (Basafa et al. 2013, "Comparison with experiments"): the
// post-injection CT registered onto the pre-injection CT, the cement segmented in it (and in a simulated CT
// on the pre grid, when given), and the two compared: the paper's surface error (larger of the two directed
// mean distances), Hausdorff and its 95th percentile, Dice and Jaccard, cement volume, mean spreading
// distance from the injection point, centroid offset. Computing and writing are separate, so that nothing
// is written until everything is computed, and metrics.json's schema lives here rather than in the command.
#pragma once

#include "cementsph/imaging/AffineRegistration.h"
#include "cementsph/imaging/CementSegmentation.h"
#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/study/AnalysedCement.h"
#include "cementsph/surfacemetrics/Isosurface.h"
#include "cementsph/surfacemetrics/SurfaceDistance.h"
#include "cementsph/surfacemetrics/VolumeMetrics.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace cementsph::study {

// The inputs, as `cementsph compare`'s options give them.
struct CementComparisonRequest {
  std::string pre, post, simulated; // volume files or DICOM folders; simulated may be empty
  std::vector<double> injectionMm;  // injection point (x, y, z) in the pre CT's physical space
  std::optional<double> thresholdHU; // a fixed difference threshold instead of half the contrast
  double closingMm = 0.0;
  double searchRadiusMm = imaging::SegmentationOptions{}.injectionSearchRadiusMm;
  double smoothingVoxels = surfacemetrics::IsosurfaceOptions{}.smoothingSigmaVoxels; // Gaussian sigma, voxels
  bool registration = true; // false: post is already aligned (only resampled onto pre's grid)
  bool maskCement = true;   // registration: keep bright (cement) voxels of post out of the metric
};

// What the comparison computed. metrics is metrics.json's content (without render_backend, which the
// pictures add); timingS the seconds of each step (read_s, registration_s, segmentation_s, surface_metrics_s,
// write_s, total_s: the last two once written).
struct CementComparison {
  imaging::ImageType::Pointer pre, registered, simulated; // simulated on pre's grid; null without one
  // `inject`'s cement_labels.nrrd beside the simulated CT (which cement leaked: surfaces.png draws it red), as
  // read; null without a simulated CT or without that file.
  imaging::ImageType::Pointer simulatedLabels;
  std::optional<imaging::RegistrationResult> registration;
  AnalysedCement ct;
  std::optional<AnalysedCement> sim;
  std::optional<surfacemetrics::Overlap> overlap;            // with a simulated CT
  std::optional<surfacemetrics::SurfaceComparison> surfaces; // when both have cement
  std::optional<double> centroidOffsetMm;                    // when both have cement
  std::vector<std::string> warnings;
  std::map<std::string, double> timingS;
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now(); // total_s counts from here
  nlohmann::json metrics;
};

// Reads, registers, segments and measures. Throws std::runtime_error for an injection point outside the pre
// volume or a simulated volume that does not overlap it, std::invalid_argument (naming --post) when the post
// scan has no cement at the injection point.
CementComparison compareCement(const CementComparisonRequest& request);

// Writes into the folder out (created): registered_post.nrrd, pre_to_post.tfm (with registration),
// cement_ct_mask.nrrd, cement_ct_surface.vtp, the same for the simulated CT, and metrics.json (with timing and
// provenance), every file atomically.
void writeCementComparison(CementComparison& comparison, const std::filesystem::path& out);

// Rewrites out/metrics.json from comparison.metrics (after the pictures added render_backend).
void writeCementComparisonMetrics(const CementComparison& comparison, const std::filesystem::path& out);

} // namespace cementsph::study
