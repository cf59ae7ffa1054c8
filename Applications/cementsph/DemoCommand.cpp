// cementsph demo: the whole product on bundled data, in seconds. The foam phantom pair of
// Data/foam-phantom (made by `cementsph phantom`), an injection with the paper's plan (its scene preset,
// with the volume, rate, viscosity and tip the phantom's post scan was made with: its truth.json's plan, read by
// the Phantom module),
// then the comparison against the phantom's post-injection CT (registration, segmentation, surfaces,
// metrics, pictures), the X-ray sequences of the simulation and of the experiment (its pre- and registered
// post-injection CTs as the first and last frames; paper Fig. 12) and the tip-pressure plot (Fig. 10).
// It runs the `inject`, `compare` and `xray` subcommands themselves, so the demo is exactly what a user
// gets from them. DIR/metrics.json gathers the headline figures of the three. The phantom's post scan was
// itself made by the model (cementsph phantom), so the comparison checks the pipeline; it is not a validation
// of the model, and metrics.json and the last line say so (post_scan_made_by).
#include "cementsph/provenance/Provenance.h"
#include "CommandRegistry.h"
#include "CommandRequests.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/phantom/PhantomFiles.h"
#include "cementsph/scene/SceneSettings.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace {

namespace fs = std::filesystem;

struct DemoOptions {
  std::string dataDir = CEMENTSPH_DATA_DIR;
  std::string out = "out/demo";
  int threads = 0;
  bool vertebra = false;
};

std::string vec3(const nlohmann::json& v) {
  std::ostringstream s;
  s.precision(10);
  s << v.at(0).get<double>() << ',' << v.at(1).get<double>() << ',' << v.at(2).get<double>();
  return s.str();
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The plan's tip, volume, rate and viscosity as scene settings.
cementsph::scene::SceneSettings planSettings(const cementsph::phantom::PhantomInjectionPlan& plan) {
  cementsph::scene::SceneSettings settings;
  settings.tipMm = plan.tipMm;
  settings.volumeMl = plan.volumeMl;
  settings.flowRateMlPerS = plan.flowRateMlPerS;
  settings.viscosityPaS = plan.viscosityPaS;
  return settings;
}

void printVertebraSummary(const nlohmann::json& m, const fs::path& out) {
  std::cout << "demo --vertebra: " << m.at("bone_model").get<std::string>() << " bone (porosity at the tip "
            << m.at("porosity_at_tip").get<double>() << "), " << m.at("cement_volume_ml").get<double>()
            << " ml injected, syringe pressure " << m.at("injection_pressure_pa").get<double>() * 1e-6 << " MPa; leakage "
            << m.at("leakage_volume_ml").get<double>() << " ml at " << m.at("leakage_sites").size() << " site(s)";
  for (const auto& s : m.at("leakage_sites"))
    std::cout << "; " << s.at("volume_ml").get<double>() << " ml at (" << vec3(s.at("position_mm")) << ") mm from "
              << s.at("first_time_s").get<double>() << " s";
  std::cout << ". Files: " << (out / "metrics.json").string() << ", " << (out / "inject").string() << "\n";
}

// demo --vertebra: the clinical vertebra phantom read as its DICOM series, 4 ml by the transpedicular plan of
// its truth.json, with the continuum bone model and the leakage report.
int runVertebraDemo(const DemoOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path phantom = fs::path(o.dataDir) / "vertebra-phantom";
  const cementsph::phantom::PhantomInjectionPlan plan = cementsph::phantom::readInjectionPlan(phantom);
  if (!plan.direction) throw std::runtime_error((phantom / "truth.json").string() + ": injection.direction is missing");
  const fs::path out(o.out);
  std::cerr << "demo --vertebra: injecting " << plan.volumeMl
            << " ml into the clinical vertebra phantom (DICOM series, 1 x 1 x 1.5 mm voxels) by a transpedicular plan\n";
  cementsph::app::InjectRequest inject;
  inject.ct = (phantom / "pre_dicom").string();
  inject.scene = (fs::path(o.dataDir) / "scenes" / "paper.json").string();
  inject.settings = planSettings(plan);
  inject.settings.direction = plan.direction;
  inject.threads = o.threads;
  inject.out = (out / "inject").string();
  nlohmann::json m;
  const int rc = cementsph::app::runInject(inject, &m);
  if (rc != 0 && rc != 3) return rc;
  nlohmann::json summary;
  for (const char* k : {"bone_model", "bone_model_reason", "porosity_at_tip", "permeability_at_tip_m2", "volume_injected_ml",
                        "cement_volume_ml", "mean_spreading_distance_mm", "final_tip_pressure_pa", "max_tip_pressure_pa",
                        "injection_pressure_pa", "leakage_volume_ml", "leakage_sites", "wall_time_s"})
    summary[k] = m.contains(k) ? m[k] : nlohmann::json(nullptr);
  summary["wall_time_s"] = secondsSince(start);
  summary["provenance"] = cementsph::provenance::toJson();
  cementsph::imaging::writeTextAtomically((out / "metrics.json").string(), summary.dump(2) + "\n");
  printVertebraSummary(m, out);
  return rc;
}

nlohmann::json pick(const nlohmann::json& from, std::initializer_list<const char*> keys) {
  nlohmann::json j;
  for (const char* k : keys) j[k] = from.contains(k) ? from[k] : nlohmann::json(nullptr);
  return j;
}

// The metrics of the three steps.
struct DemoMetrics {
  nlohmann::json inject, compare, xray;
};

// DIR/metrics.json: the headline figures of the three steps.
nlohmann::json demoSummary(const DemoMetrics& m, double wallS) {
  nlohmann::json metrics;
  metrics["inject"] = pick(m.inject, {"volume_injected_ml", "simulated_time_s", "wall_time_s", "real_time_factor",
                                      "max_tip_pressure_pa", "mean_spreading_distance_mm"});
  metrics["compare"] = pick(m.compare, {"error_mm", "hausdorff95_mm", "dice", "jaccard", "cement_volume_ml"});
  metrics["xray"] = pick(m.xray, {"final_time_s", "final_projected_area_mm2", "final_reference_projected_area_mm2"});
  const nlohmann::json& finalFrame = m.xray.at("final_frame");
  metrics["xray"]["final_frame_dice"] = finalFrame.is_null() ? nlohmann::json(nullptr) : finalFrame.at("dice");
  metrics["xray"]["final_frame_iou"] = finalFrame.is_null() ? nlohmann::json(nullptr) : finalFrame.at("iou");
  metrics["post_scan_made_by"] = "the model itself (pipeline check, not a validation)";
  metrics["wall_time_s"] = wallS;
  metrics["provenance"] = cementsph::provenance::toJson();
  return metrics;
}

// The three subcommands in turn; false (with *rc their status) when one failed outright. A status 3 (a picture
// failed, its numbers are written) goes on and is reported at the end in *status.
bool runFoamSteps(const DemoOptions& o, const fs::path& phantom, const cementsph::phantom::PhantomInjectionPlan& plan,
                  DemoMetrics& m, int* rc, int* status) {
  auto step = [&](int code) {
    *rc = code;
    if (code == 3) *status = 3;
    return code == 0 || code == 3;
  };
  const fs::path out(o.out);
  std::cerr << "demo 1/4: injecting " << plan.volumeMl << " ml at " << plan.flowRateMlPerS << " ml/s, "
            << plan.viscosityPaS << " Pa.s into the foam phantom (paper's plan), with a simulated CT every second\n";
  cementsph::app::InjectRequest inject;
  inject.ct = (phantom / "pre.nrrd").string();
  inject.scene = (fs::path(o.dataDir) / "scenes" / "paper.json").string();
  inject.settings = planSettings(plan);
  inject.settings.simulatedCtSnapshots = true;
  inject.threads = o.threads;
  inject.out = (out / "inject").string();
  if (!step(cementsph::app::runInject(inject, &m.inject))) return false;

  std::cerr << "demo 2/4: comparing with the phantom's post-injection CT\n";
  cementsph::app::CompareRequest compare;
  compare.pre = (phantom / "pre.nrrd").string();
  compare.post = (phantom / "post.nrrd").string();
  compare.simulated = (out / "inject" / "simulated_ct.nrrd").string();
  compare.injection = {plan.tipMm[0], plan.tipMm[1], plan.tipMm[2]};
  compare.out = (out / "compare").string();
  if (!step(cementsph::app::runCompare(compare, &m.compare))) return false;

  // The experiment's X-ray sequence has two frames: the pre-injection CT (t = 0) and the registered
  // post-injection CT, taken as the frame at the end of the injection (the simulation's last frame).
  std::cerr << "demo 3/4: X-ray sequences (Fig. 12): the simulation's frames and the post-injection CT's\n";
  cementsph::app::XrayRequest xrayRequest;
  xrayRequest.sequence = {(out / "inject").string()};
  xrayRequest.reference = {(phantom / "pre.nrrd").string(), (out / "compare" / "registered_post.nrrd").string()};
  xrayRequest.referenceTimesS = {0.0, m.inject.at("simulated_time_s").get<double>()};
  xrayRequest.drr.threads = o.threads;
  xrayRequest.out = (out / "xray").string();
  return step(cementsph::app::runXray(xrayRequest, &m.xray));
}

int runDemo(const DemoOptions& o) {
  if (o.vertebra) return runVertebraDemo(o);
  const auto start = std::chrono::steady_clock::now();
  const fs::path phantom = fs::path(o.dataDir) / "foam-phantom";
  const cementsph::phantom::PhantomInjectionPlan plan = cementsph::phantom::readInjectionPlan(phantom);
  const fs::path out(o.out);
  DemoMetrics m;
  int rc = 0, status = 0;
  if (!runFoamSteps(o, phantom, plan, m, &rc, &status)) return rc;

  std::cerr << "demo 4/4: summary\n";
  for (const char* picture : {"tip_pressure.png", "injection_pressure.png"}) {
    std::error_code ec;
    fs::copy_file(out / "inject" / picture, out / picture, fs::copy_options::overwrite_existing, ec);
    if (ec) {
      std::cerr << "cementsph demo: picture " << picture << " not copied: " << ec.message() << "\n";
      status = 3;
    }
  }
  const double wall = secondsSince(start);
  cementsph::imaging::writeTextAtomically((out / "metrics.json").string(), demoSummary(m, wall).dump(2) + "\n");
  std::cout << "demo done in " << wall << " s: " << (out / "metrics.json").string() << ", "
            << (out / "compare" / "surfaces.png").string() << ", " << (out / "compare" / "slices.png").string()
            << ", " << (out / "xray" / "xray_frames.png").string() << ", " << (out / "tip_pressure.png").string()
            << "; particles for ParaView: " << (out / "inject" / "particles.pvd").string()
            << ". The post scan compared with was made by the model itself: a pipeline check, not a validation.\n";
  return status;
}

cementsph::app::CommandRunner setupDemo(CLI::App& sub) {
  auto o = std::make_shared<DemoOptions>();
  sub.add_option("--out", o->out, "output folder (inject/, compare/, xray/, metrics.json, tip_pressure.png)")->capture_default_str();
  sub.add_option("--data-dir", o->dataDir, "folder holding foam-phantom/ and scenes/")->capture_default_str();
  sub.add_option("--threads", o->threads, "OpenMP threads (0: the cores the load average leaves free)");
  sub.add_flag("--vertebra", o->vertebra,
               "the clinical vertebra phantom instead: 4 ml by a transpedicular plan, the leakage report");
  return [o] { return runDemo(*o); };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(demo, "demo",
                           "Bundled foam phantom -> injection (paper's plan) -> comparison with its post CT, pictures",
                           setupDemo)
