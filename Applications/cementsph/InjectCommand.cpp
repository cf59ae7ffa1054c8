// cementsph inject: an injection simulation in a CT (Basafa et al. 2013, "Simulations"). The CT's voxels
// above threshold_hu near the pores become fixed particles; cement is emitted at the cannula tip until the
// scene's volume is in. Writes DIR/metrics.json, tip_pressure.csv, particles_NNNN.vtp + particles.pvd,
// simulated_ct.nrrd and scene.json (Modules/Simulation/CTScene/.../InjectionRunner.h; docs/scene-figures.md),
// then the pictures that fit an injection: tip_pressure.png (paper Fig. 10), injection_pressure.png (syringe,
// cannula and outlet pressures over time), with a label map (continuum bone) cement_slices.png and
// cement_surface.png (leaked cement red), and, when the scene key
// simulated_ct_snapshots is on, the X-ray sequence of the snapshots in DIR/xray (`cementsph xray`, Fig. 12).
// The pictures draw the run in memory (the filter's typed result and outputs; the X-ray frames projected as the
// run makes them), never the files it has just written.
// A failed picture is one line on stderr and exit status 3 (the numbers are written), as in `compare`.
#include "CommandRegistry.h"
#include "CommandRequests.h"
#include "OutputFiles.h"
#include "SceneOverrides.h"

#include "cementsph/rendering/CementPictureLayout.h"
#include "cementsph/rendering/CementSlices.h"
#include "cementsph/rendering/CementSurface.h"
#include "cementsph/rendering/TipPressurePlot.h"

#include "cementsph/drr/XraySequence.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/RunEstimate.h"
#include "cementsph/scene/SceneConfig.h"
#include "vtkSPHInjectionFilter.h"

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <exception>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>

namespace {

struct InjectArgs {
  cementsph::app::InjectRequest request;
  cementsph::app::SceneOverrideArgs overrides;
};

cementsph::app::CommandRunner setupInject(CLI::App& sub) {
  auto a = std::make_shared<InjectArgs>();
  sub.add_option("--ct", a->request.ct, "CT volume in HU (file: .nrrd .mha .nii .nii.gz, or a DICOM directory)")->required();
  sub.add_option("--scene", a->request.scene, "Scene file (JSON; keys name their units, see docs/scene-figures.md)")
      ->required();
  sub.add_option("--out", a->request.out, "Output directory (created; existing files are replaced)")->required();
  cementsph::app::addSceneOverrideOptions(sub, a->overrides);
  sub.add_option("--threads", a->request.threads, "OpenMP threads (0: the cores the load average leaves free)");
  sub.add_option("--labels", a->request.labels,
                 "Label map on the CT's grid (e.g. TotalSegmentator's or a 3D Slicer segmentation) for the tissue "
                 "classes instead of the CT bone rule (scene key labels_path; label_table says which label is what)");
  sub.add_flag("--quiet", a->request.quiet, "No progress line");
  sub.add_flag("--allow-large", a->request.allowLarge,
               "Run even when the estimated work is hours (or memory over half the RAM); docs: README 'Bad input'");
  sub.add_flag("--no-pictures", a->request.noPictures,
               "Do not write tip_pressure.png (Fig. 10), injection_pressure.png, cement_slices.png, cement_surface.png nor, with simulated_ct_snapshots, the X-ray sequence "
               "in DIR/xray (Fig. 12)");
  return [a, &sub]() {
    // Flags given on the command line override the scene file (and --set).
    a->request.settings = cementsph::app::sceneSettings(sub, a->overrides);
    return cementsph::app::namingTheOptions(sub, a->request.scene, [&] { return cementsph::app::runInject(a->request); });
  };
}

} // namespace

namespace cementsph::app {

namespace {

namespace fs = std::filesystem;

// What a run gives the pictures: its typed result (summary, outlet series; InjectionRunner.h), and its simulated CT
// and cement label map on the input CT's grid (the filter's output ports 0 and 1; the same voxels as
// simulated_ct.nrrd and cement_labels.nrrd).
struct InjectRun {
  scene::InjectionRunResult result;
  vtkSmartPointer<vtkImageData> simulatedCt, cementLabels;
  // The vertebra on the same grid: the --labels map (its label label_table's target_vertebra, or -1: the label
  // at the tip), else the anatomy the run judged leakage by (the result's, as anatomy_labels.nrrd holds it: the
  // target vertebra 1); null when the run had none (the HU rule).
  vtkSmartPointer<vtkImageData> vertebra;
  int vertebraLabel = -1;
};

// The largest leakage site of the run, if any leaked.
std::optional<std::array<double, 3>> largestLeakMm(const scene::InjectionSummary& s) {
  std::optional<std::array<double, 3>> at;
  double largest = 0;
  for (const scene::LeakageSite& site : s.leakageSites)
    if (site.volumeMl > largest) {
      largest = site.volumeMl;
      at = site.positionMm;
    }
  return at;
}

// cement_slices.png: through the largest leak if there is one, else through the tip; the cannula, each leak in its
// site class's colour (the run's nearest site) and the target vertebra's outline (--labels or the bone rule's).
void drawCementSlices(const InjectRun& run, const scene::SceneConfig& scene, const fs::path& png) {
  rendering::InjectionMarks marks; // the same marks as plan's best/cement_slices.png
  marks.tipMm = {scene.tipMm->x(), scene.tipMm->y(), scene.tipMm->z()};
  marks.direction = {scene.direction.x(), scene.direction.y(), scene.direction.z()};
  for (const scene::LeakageSite& site : run.result.summary.leakageSites)
    marks.leaks.push_back({{site.positionMm, site.siteClass}, site.volumeMl});
  // The vertebra's outline, with or without --labels.
  marks.vertebraMask = run.vertebra;
  marks.vertebraLabel = run.vertebraLabel;
  rendering::writeCementSlices(run.simulatedCt, run.cementLabels, marks.centreMm(), png, marks.options());
}

// cement_surface.png: the cement's surface, in bone blue, leaked red (CementSurface.h), seen from the side of the
// largest leak (from the tip towards it, a little from above), so the cement in bone does not hide it.
void drawCementSurface(const InjectRun& run, const scene::SceneConfig& scene, const fs::path& png) {
  const scene::InjectionSummary& s = run.result.summary;
  rendering::CementSurfaceOptions options;
  const std::array<double, 3> tipMm{scene.tipMm->x(), scene.tipMm->y(), scene.tipMm->z()};
  if (const auto leak = largestLeakMm(s))
    if (const auto view = rendering::viewTowards(tipMm, *leak)) std::copy(view->begin(), view->end(), options.viewDirection);
  options.note = rendering::leakNote(s.leakageVolumeMl, s.leakageSites.size());
  // The vertebra around the cement, translucent: its label, or (--labels without target_vertebra) the one at the tip.
  options.vertebraMask = run.vertebra;
  options.vertebraLabel = run.vertebraLabel;
  if (run.vertebra && run.vertebraLabel < 0) {
    options.vertebraLabel = rendering::labelAt(run.vertebra, tipMm);
    if (options.vertebraLabel == 0) options.vertebraMask = nullptr; // the tip is in no labelled structure
  }
  rendering::writeCementSurface(run.cementLabels, png, options);
}

void printSummary(const scene::InjectionSummary& s, const std::string& out) {
  const double realTimeFactor = s.wallTimeS > 0 ? s.simulatedTimeS / s.wallTimeS : 0.0; // as metrics.json's
  std::cout << "injected " << s.volumeInjectedMl << " ml in " << s.steps << " steps, " << s.wallTimeS
            << " s wall (real-time factor " << realTimeFactor << "); model " << s.engine << ", " << s.cementPoints
            << (s.particles ? " particles" : " voxels holding cement")
            << (s.particles ? ", " + std::to_string(s.particles->escaped) + " left the region" : std::string())
            << "; results in " << out << "\n";
}

// The outlet's series as tip_pressure.csv holds it, from the run in memory (the plots draw it, not the file).
rendering::TipPressureSeries tipPressureSeries(const scene::InjectionRunResult& r) {
  rendering::TipPressureSeries series;
  for (const scene::TipRecord& t : r.tipSeries) {
    series.timeS.push_back(t.time);
    series.pressurePa.push_back(t.tipPa);
    series.pressureMinusBaselinePa.push_back(t.tipPa - r.summary.tipPressureBaselinePa);
    series.cannulaPa.push_back(t.cannulaPa);
    series.injectionPa.push_back(t.tipPa + t.cannulaPa);
  }
  return series;
}

// inject's X-ray sequence (`cementsph xray` of the output folder), each frame projected as the run makes it
// (InjectionRunOptions::onCtFrame), so no frame volume is read back nor held. A failed projection is the picture
// step's failure (exit status 3), not the run's.
struct XrayProjection {
  XrayRequest request;
  std::optional<drr::Vec3> tipMm;
  std::shared_ptr<drr::XraySequence> sequence;
  std::exception_ptr error;
  double seconds = 0;

  XrayProjection(const InjectRequest& a, const scene::SceneConfig& scene) {
    request.sequence = {a.out};
    request.out = (fs::path(a.out) / "xray").string();
    request.drr.threads = a.threads;
    tipMm = drr::Vec3{scene.tipMm->x(), scene.tipMm->y(), scene.tipMm->z()}; // as the folder's scene.json has it
  }
  void add(double timeS, const imaging::ImageType& frame) {
    if (error) return;
    const auto start = std::chrono::steady_clock::now();
    try {
      if (!sequence)
        sequence = std::make_shared<drr::XraySequence>(
            xraySequenceOptions(request, imaging::geometryOf(&frame).physicalBounds(), tipMm));
      sequence->addFrame(timeS, imaging::toVtk(&frame));
    } catch (...) {
      error = std::current_exception();
    }
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  // The xray/ folder from the projected frames (the frame list and the rest as `cementsph xray` makes them).
  void write() const {
    if (error) std::rethrow_exception(error);
    XrayRequest r = request;
    r.projected = sequence;
    r.projectedSeconds = seconds;
    if (runXray(r) != 0) throw std::runtime_error("see the lines above");
  }
};

// The run goes through the VTK algorithm (the same runner a VTK pipeline gets), which writes the files; returns
// its typed result and its outputs in memory, which the pictures draw (rather than reading back the files).
InjectRun runFilter(const InjectRequest& a, const scene::SceneConfig& scene, XrayProjection* xray) {
  const auto image = imaging::readVolume(a.ct);
  const auto spacing = image->GetSpacing();
  const std::string note =
      scene::checkRunSize(scene::estimateRun(scene, spacing[0] * spacing[1] * spacing[2]), a.allowLarge);
  if (!note.empty() && !a.quiet) std::cerr << "cementsph inject: " << note << "\n";
  auto filter = vtkSmartPointer<vtkSPHInjectionFilter>::New();
  filter->SetInputDataObject(0, imaging::toVtk(image));
  filter->SetScene(scene);
  filter->SetOutputDirectory(a.out);
  filter->SetPrintProgress(!a.quiet);
  if (xray) filter->SetCtFrameObserver([xray](double t, const imaging::ImageType& frame) { xray->add(t, frame); });
  filter->Update();
  filter->RethrowIfFailed();
  InjectRun run;
  run.result = *filter->GetResult();
  run.simulatedCt = filter->GetSimulatedCTOutput();
  run.cementLabels = filter->GetLabelMapOutput();
  if (!scene.labelsPath.empty()) {
    run.vertebra = imaging::toVtk(imaging::readVolume(scene.labelsPath).GetPointer()); // the user's input
    if (scene.labelTable.is_object()) run.vertebraLabel = scene.labelTable.value("target_vertebra", -1);
  } else if (run.result.anatomyLabelsFile) {
    run.vertebra = imaging::toVtk(run.result.anatomyLabelsFile.GetPointer());
    run.vertebraLabel = 1; // anatomy::TissueClass
  }
  return run;
}

} // namespace

int runInject(const InjectRequest& a, scene::InjectionRunResult* result) {
  scene::SceneConfig scene = scene::loadSceneFile(a.scene, a.settings);
  if (!a.labels.empty()) {
    scene.labelsPath = a.labels;
    scene.explicitKeys.insert("labels_path"); // set by the user, so an engine that ignores it says so
  }
  if (a.threads > 0) omp_set_num_threads(a.threads);
  std::optional<XrayProjection> xray;
  if (scene.simulatedCtSnapshots && !a.noPictures) xray.emplace(a, scene);
  const InjectRun run = runFilter(a, scene, xray ? &*xray : nullptr);
  if (result) *result = run.result;
  printSummary(run.result.summary, a.out);
  if (a.noPictures) return 0;
  const fs::path out(a.out);
  PictureSteps pictures("inject");
  auto announce = [](const fs::path& png) { std::cout << "wrote " << png.string() << "\n"; };
  auto step = [&](const std::string& name, const std::function<void(const fs::path&)>& draw) {
    pictures.draw(name, out / name, [&](const fs::path& png) {
      draw(png);
      announce(png);
    });
  };
  const rendering::TipPressureSeries tip = tipPressureSeries(run.result);
  step("tip_pressure.png", [&](const fs::path& png) { rendering::writeTipPressurePlot(tip, png); });
  // Only an engine that labels its cement (the driver then wrote cement_labels.nrrd) gets the label pictures.
  if (run.result.cementLabels) {
    step("cement_slices.png", [&](const fs::path& png) { drawCementSlices(run, scene, png); });
    step("cement_surface.png", [&](const fs::path& png) { drawCementSurface(run, scene, png); });
  }
  step("injection_pressure.png",
       [&](const fs::path& png) { rendering::writeInjectionPressurePlot(tip, png); });
  if (xray) pictures.draw("xray/", out / "xray", [&](const fs::path&) { xray->write(); });
  return pictures.status();
}

} // namespace cementsph::app

CEMENTSPH_REGISTER_COMMAND(inject_command, "inject",
                           "Simulate a cement injection into a CT's pores (scene file: cannula, rate, volume, "
                           "viscosity); particles, tip pressure, simulated CT",
                           setupInject)
