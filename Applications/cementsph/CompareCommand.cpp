// `cementsph compare`: registers the post-injection CT onto the pre-injection CT, segments the cement
// in it (and, when given, in a simulated CT on the pre grid), and compares them: the paper's surface
// error (larger of the two directed mean distances), Hausdorff and its 95th percentile, Dice and
// Jaccard, cement volume, mean spreading distance from the injection point, centroid offset.
// A thin layer over CementSPH::Study's CementComparison.h (which computes, then writes metrics.json and the
// volumes): this file parses the options, draws the pictures and prints the summary.
// Nothing is written until everything is computed, and every file is written atomically.
#include "CommandRegistry.h"
#include "CommandRequests.h"
#include "OutputFiles.h"

#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/rendering/CementPictureLayout.h"
#include "cementsph/rendering/RenderBackend.h"
#include "cementsph/rendering/SliceComparison.h"
#include "cementsph/rendering/SurfaceComparison.h"
#include "cementsph/study/CementComparison.h"
#include "cementsph/study/ScanProvenance.h"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <utility>

namespace {

namespace fs = std::filesystem;
using cementsph::study::CementComparison;

// slices.png: axial slices through the segmented cement (either one), every 5 mm as in the paper's Fig. 11.
void drawSlices(const CementComparison& c, double injectionZMm, const std::string& postLabel, const fs::path& png) {
  cementsph::rendering::SliceComparisonOptions options;
  options.postRowName = postLabel;
  // The cement's z range in either scan; no cement anywhere: one slice through the injection point still shows
  // where it should be.
  options.zRangeMm =
      cementsph::rendering::surfacesZRangeMm({c.ct.surface.Get(), c.sim ? c.sim->surface.Get() : nullptr}, injectionZMm);
  auto simulatedVtk = c.simulated ? cementsph::imaging::toVtk(c.simulated.GetPointer()) : nullptr;
  cementsph::rendering::renderSliceComparison(cementsph::imaging::toVtk(c.registered.GetPointer()), simulatedVtk,
                                              png, 5.0, options);
}

// surfaces.png: the CT and simulated isosurfaces and the distance between them (Fig. 7).
void drawSurfaces(const CementComparison& c, const std::string& postLabel, const fs::path& png) {
  // `inject`'s label map beside the simulated CT (continuum bone): leaked cement red.
  cementsph::rendering::SurfaceComparisonOptions options;
  // options holds a raw pointer: the VTK copy must outlive the rendering.
  const auto labels = c.simulatedLabels ? cementsph::imaging::toVtk(c.simulatedLabels.GetPointer()) : nullptr;
  options.simulationLabels = labels;
  options.postTitle = postLabel;
  cementsph::rendering::renderSurfaceComparison(c.ct.surface, c.sim->surface, png, options);
}

void printSummary(const CementComparison& c, const fs::path& out) {
  if (c.registration) std::cout << "registration (post -> pre):\n" << cementsph::imaging::formatRegistrationReport(*c.registration);
  char line[200];
  auto row = [&](const char* name, const char* unit, double ctValue, std::optional<double> simValue) {
    if (simValue)
      std::snprintf(line, sizeof line, "  %-28s %-4s %12.3f %12.3f\n", name, unit, ctValue, *simValue);
    else
      std::snprintf(line, sizeof line, "  %-28s %-4s %12.3f\n", name, unit, ctValue);
    std::cout << line;
  };
  const auto& sim = c.sim;
  std::cout << "cement:" << (sim ? "                                    CT    simulated\n" : "\n");
  row("volume", "ml", c.ct.segmentation.volumeMl, sim ? std::optional<double>(sim->segmentation.volumeMl) : std::nullopt);
  row("mean spreading distance", "mm", c.ct.spreadingMm, sim ? std::optional<double>(sim->spreadingMm) : std::nullopt);
  if (c.surfaces) {
    std::cout << "comparison:\n";
    row("mean distance CT->sim", "mm", c.surfaces->aToB.meanMm, std::nullopt);
    row("mean distance sim->CT", "mm", c.surfaces->bToA.meanMm, std::nullopt);
    row("error (larger mean)", "mm", c.surfaces->errorMm, std::nullopt);
    row("Hausdorff", "mm", c.surfaces->hausdorffMm, std::nullopt);
    row("Hausdorff 95 %", "mm", c.surfaces->hausdorff95Mm, std::nullopt);
    row("Dice", "", c.overlap->dice, std::nullopt);
    row("Jaccard", "", c.overlap->jaccard, std::nullopt);
    row("centroid offset", "mm", *c.centroidOffsetMm, std::nullopt);
  }
  for (const auto& w : c.warnings) std::cerr << "cementsph compare: warning: " << w << "\n";
  std::cout << "wrote " << (out / "metrics.json").string() << " (" << c.timingS.at("total_s") << " s)\n";
}

cementsph::app::CommandRunner setupCompare(CLI::App& sub) {
  auto a = std::make_shared<cementsph::app::CompareRequest>();
  auto forcedThresholdHU = std::make_shared<double>(0.0);
  sub.add_option("--pre", a->pre, "Pre-injection CT (file: .nrrd .mha .nii .nii.gz, or DICOM directory)")
      ->required();
  sub.add_option("--post", a->post, "Post-injection CT (file or DICOM directory)")->required();
  sub.add_option("--simulated", a->simulated,
                 "Simulated post-injection CT (voxelised particles, HU) on the pre CT's grid; a cement_labels.nrrd "
                 "beside it (inject, continuum bone) draws leaked cement red in surfaces.png");
  sub.add_option("--injection-point-mm", a->injection,
                 "Injection point (cannula tip) in the pre CT's physical space, mm: x,y,z")
      ->required()
      ->delimiter(',')
      ->expected(3);
  sub.add_option("--out", a->out, "Output directory (created; existing files are replaced)")->required();
  CLI::Option* forcedThreshold =
      sub.add_option("--threshold-hu", *forcedThresholdHU,
                     "Cement = (registered post - pre) above this fixed value, HU (default: half the cement's "
                     "own contrast, estimated from the data; metrics.json reports it as cement_threshold_hu)");
  sub.add_option("--closing-radius-mm", a->closingMm,
                 "Morphological closing of the cement mask, ball radius in mm (0: none)")
      ->capture_default_str();
  sub.add_option("--injection-search-radius-mm", a->searchRadiusMm,
                 "If no cement is at the injection point, keep the nearest within this distance, mm")
      ->capture_default_str();
  sub.add_option("--surface-smoothing-voxels", a->smoothingVoxels,
                 "Gaussian sigma applied to masks before isosurfacing, voxels (0: staircase)")
      ->capture_default_str();
  sub.add_flag("--no-registration", a->noRegistration,
               "POST is already aligned with PRE (it is only resampled onto PRE's grid)");
  sub.add_flag("--no-cement-mask", a->noCementMask,
               "Registration: do not exclude bright (cement) voxels of POST from the metric");
  sub.add_flag("--no-pictures", a->noPictures,
               "Do not write slices.png (axial slices every 5 mm, CT above simulated, paper Fig. 11) and "
               "surfaces.png (CT and simulated isosurfaces and the distance between them, Fig. 7)");

  return [a, forcedThreshold, forcedThresholdHU]() {
    if (forcedThreshold->count() > 0) a->thresholdHU = *forcedThresholdHU;
    return cementsph::app::runCompare(*a);
  };
}

} // namespace

namespace cementsph::app {

int runCompare(const CompareRequest& a, study::CementComparison* result) {
  study::CementComparisonRequest request;
  request.pre = a.pre;
  request.post = a.post;
  request.simulated = a.simulated;
  request.injectionMm = a.injection;
  request.thresholdHU = a.thresholdHU;
  request.closingMm = a.closingMm;
  request.searchRadiusMm = a.searchRadiusMm;
  request.smoothingVoxels = a.smoothingVoxels;
  request.registration = !a.noRegistration;
  request.maskCement = !a.noCementMask;
  CementComparison comparison = study::compareCement(request);
  const fs::path out(a.out);
  study::writeCementComparison(comparison, out);

  // Pictures, after metrics.json so a rendering failure never loses the numbers.
  PictureSteps pictures("compare", "metrics");
  // The post scan named by what it is (a phantom's is simulated, never "experiment"): ScanProvenance.h.
  const std::string postLabel = study::postScanLabel(a.post);
  if (!a.noPictures) {
    pictures.drawAndAnnounce("slices.png", out / "slices.png", [&](const fs::path& png) {
      drawSlices(comparison, a.injection[2], postLabel, png);
    });
    if (comparison.surfaces)
      pictures.drawAndAnnounce("surfaces.png", out / "surfaces.png", [&](const fs::path& png) {
        drawSurfaces(comparison, postLabel, png);
      });
  }
  // Which off-screen backend drew the pictures (OSMesa, surfaceless EGL or an X display), in metrics.json.
  if (const auto backend = rendering::lastRenderBackend()) {
    comparison.metrics["render_backend"] = rendering::renderBackendName(*backend);
    study::writeCementComparisonMetrics(comparison, out);
  }
  printSummary(comparison, out);
  if (result) *result = std::move(comparison);
  return pictures.status();
}

} // namespace cementsph::app

CEMENTSPH_REGISTER_COMMAND(compare_command, "compare",
                           "Register post- to pre-injection CT, segment the cement, compare with a "
                           "simulated CT",
                           setupCompare)
