// cementsph inject: an injection simulation in a CT (Basafa et al. 2013, "Simulations"). The CT's voxels
// above threshold_hu near the pores become fixed particles; cement is emitted at the cannula tip until the
// scene's volume is in. Writes DIR/metrics.json, tip_pressure.csv, particles_NNNN.vtp + particles.pvd,
// simulated_ct.nrrd and scene.json (Modules/Simulation/CTScene/.../InjectionRunner.h; docs/scene-figures.md),
// then the pictures that fit an injection: tip_pressure.png (paper Fig. 10), injection_pressure.png (syringe,
// cannula and outlet pressures over time), with a label map (continuum bone) cement_slices.png and
// cement_surface.png (leaked cement red), and, when the scene key
// simulated_ct_snapshots is on, the X-ray sequence of the snapshots in DIR/xray (`cementsph xray`, Fig. 12).
// A failed picture is one line on stderr and exit status 3 (the numbers are written), as in `compare`.
#include "CommandRegistry.h"
#include "CommandRequests.h"
#include "SceneOverrides.h"

#include "cementsph/rendering/CementSlices.h"
#include "cementsph/rendering/CementSurface.h"
#include "cementsph/rendering/TipPressurePlot.h"

#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/RunEstimate.h"
#include "cementsph/scene/SceneConfig.h"
#include "vtkSPHInjectionFilter.h"

#include <nlohmann/json.hpp>
#include <vtkSmartPointer.h>

#include <omp.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

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
    // Flags given on the command line override the scene file (and --set), in this order.
    a->request.overrides = cementsph::app::sceneOverrides(sub, a->overrides);
    return cementsph::app::runInject(a->request);
  };
}

} // namespace

namespace cementsph::app {

int runInject(const InjectRequest& a) {
  cementsph::scene::SceneConfig scene = cementsph::scene::loadSceneFile(a.scene, a.overrides);
  if (!a.labels.empty()) scene.labelsPath = a.labels;
  if (a.threads > 0) omp_set_num_threads(a.threads);
  // The run goes through the VTK algorithm (the same runner a VTK pipeline gets), which writes the files.
  const auto image = cementsph::imaging::readVolume(a.ct);
  const auto spacing = image->GetSpacing();
  const std::string note = cementsph::scene::checkRunSize(
      cementsph::scene::estimateRun(scene, spacing[0] * spacing[1] * spacing[2]), a.allowLarge);
  if (!note.empty() && !a.quiet) std::cerr << "cementsph inject: " << note << "\n";
  const auto ct = cementsph::imaging::toVtk(image);
  auto filter = vtkSmartPointer<vtkSPHInjectionFilter>::New();
  filter->SetInputDataObject(0, ct);
  filter->SetScene(scene);
  filter->SetOutputDirectory(a.out);
  filter->SetPrintProgress(!a.quiet);
  filter->Update();
  filter->RethrowIfFailed();
  const nlohmann::json m = nlohmann::json::parse(filter->GetMetricsJSON());
  std::cout << "injected " << m["volume_injected_ml"].get<double>() << " ml in " << m["steps"] << " steps, "
            << m["wall_time_s"].get<double>() << " s wall (real-time factor " << m["real_time_factor"].get<double>()
            << "); model " << m["pressure_model"].get<std::string>() << ", " << m["cement_points"]
            << (m.contains("fluid_particles") ? " particles" : " voxels holding cement")
            << (m.contains("escaped_particles") ? ", " + m["escaped_particles"].dump() + " left the region" : std::string())
            << "; results in " << a.out << "\n";
  if (a.noPictures) return 0;
  int status = 0;
  auto picture = [&](const std::string& name, const std::function<void()>& draw) {
    try {
      draw();
    } catch (const std::exception& e) {
      std::cerr << "cementsph inject: picture " << name << " not written (the numbers are): " << e.what() << "\n";
      status = 3;
    }
  };
  const std::filesystem::path out(a.out);
  picture("tip_pressure.png", [&] {
    cementsph::rendering::writeTipPressurePlot(out / "tip_pressure.csv", out / "tip_pressure.png");
    std::cout << "wrote " << (out / "tip_pressure.png").string() << "\n";
  });
  if (std::filesystem::exists(out / "cement_labels.nrrd"))
    picture("cement_slices.png", [&] {
      // Through the largest leak if there is one (drawn red), else through the tip.
      std::array<double, 3> centre{scene.tipMm->x(), scene.tipMm->y(), scene.tipMm->z()};
      double largest = 0;
      if (m.contains("leakage_sites"))
        for (const auto& site : m["leakage_sites"])
          if (site["volume_ml"].get<double>() > largest) {
            largest = site["volume_ml"].get<double>();
            for (int axis = 0; axis < 3; ++axis) centre[std::size_t(axis)] = site["position_mm"][axis].get<double>();
          }
      const auto sim = cementsph::imaging::readVolume((out / "simulated_ct.nrrd").string());
      const auto labels = cementsph::imaging::readVolume((out / "cement_labels.nrrd").string());
      cementsph::rendering::writeCementSlices(cementsph::imaging::toVtk(sim.GetPointer()),
                                              cementsph::imaging::toVtk(labels.GetPointer()), centre,
                                              out / "cement_slices.png");
      std::cout << "wrote " << (out / "cement_slices.png").string() << "\n";
    });
  if (std::filesystem::exists(out / "cement_labels.nrrd"))
    picture("cement_surface.png", [&] {
      // The cement's surface: in bone blue, leaked red (CementSurface.h).
      const auto labels = cementsph::imaging::readVolume((out / "cement_labels.nrrd").string());
      cementsph::rendering::CementSurfaceOptions options;
      // Seen from the side of the largest leak (from the tip towards it, a little from above), so the
      // cement in bone does not hide it.
      double largest = 0;
      if (m.contains("leakage_sites"))
        for (const auto& site : m["leakage_sites"])
          if (site["volume_ml"].get<double>() > largest) {
            largest = site["volume_ml"].get<double>();
            double d[3], norm = 0;
            for (int axis = 0; axis < 3; ++axis) {
              d[axis] = site["position_mm"][axis].get<double>() - (*scene.tipMm)[axis];
              norm += d[axis] * d[axis];
            }
            norm = std::sqrt(norm);
            if (norm > 1e-6)
              for (int axis = 0; axis < 3; ++axis) options.viewDirection[axis] = d[axis] / norm + (axis == 2 ? 0.35 : 0.0);
          }
      if (m.contains("leakage_volume_ml") && m["leakage_volume_ml"].get<double>() > 0) {
        std::ostringstream leakNote;
        leakNote << std::setprecision(3) << "leaked " << m["leakage_volume_ml"].get<double>() << " ml at " << m["leakage_sites"].size()
             << (m["leakage_sites"].size() == 1 ? " site" : " sites");
        options.note = leakNote.str();
      }
      cementsph::rendering::writeCementSurface(cementsph::imaging::toVtk(labels.GetPointer()),
                                               out / "cement_surface.png", options);
      std::cout << "wrote " << (out / "cement_surface.png").string() << "\n";
    });
  picture("injection_pressure.png", [&] {
    cementsph::rendering::writeInjectionPressurePlot(out / "tip_pressure.csv", out / "injection_pressure.png");
    std::cout << "wrote " << (out / "injection_pressure.png").string() << "\n";
  });
  if (scene.simulatedCtSnapshots)
    picture("xray/", [&] {
      XrayRequest xray;
      xray.sequence = {a.out};
      xray.out = (out / "xray").string();
      xray.drr.threads = a.threads;
      if (runXray(xray) != 0) throw std::runtime_error("see the lines above");
    });
  return status;
}

} // namespace cementsph::app

CEMENTSPH_REGISTER_COMMAND(inject_command, "inject",
                           "Simulate a cement injection into a CT's pores (scene file: cannula, rate, volume, "
                           "viscosity); particles, tip pressure, simulated CT",
                           setupInject)
