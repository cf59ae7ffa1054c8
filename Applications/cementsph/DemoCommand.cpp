// cementsph demo: the whole product on bundled data, in seconds. The foam phantom pair of
// Data/foam-phantom (made by `cementsph phantom`), an injection with the paper's plan (its scene preset,
// with the volume, rate, viscosity and tip the phantom's post scan was made with: its truth.json's plan, read by
// the Phantom module),
// then the comparison against the phantom's post-injection CT (registration, segmentation, surfaces,
// metrics, pictures), the X-ray sequences of the simulation and of the experiment (its pre- and registered
// post-injection CTs as the first and last frames; paper Fig. 12) and the tip-pressure plot (Fig. 10).
// It runs the `inject`, `compare` and `xray` subcommands themselves, so the demo is exactly what a user
// gets from them. DIR/metrics.json gathers the headline figures of the three (the Study module's DemoReport.h
// writes it from their typed results). The phantom's post scan was
// itself made by the model (cementsph phantom), so the comparison checks the pipeline; it is not a validation
// of the model, and metrics.json and the last line say so (post_scan_made_by).
// First: DemoReport.h brings ITK's headers, whose own copy of Eigen must come before the system Eigen others include.
#include "cementsph/study/DemoReport.h"

#include "CommandRegistry.h"
#include "CommandRequests.h"

#include "cementsph/phantom/PhantomFiles.h"
#include "cementsph/scene/SceneSettings.h"

#include <array>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace {

namespace fs = std::filesystem;
namespace study = cementsph::study;

struct DemoOptions {
  std::string dataDir = CEMENTSPH_DATA_DIR;
  std::string out = "out/demo";
  int threads = 0;
  bool vertebra = false;
};

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

// A leak's position, x,y,z mm to ten significant digits.
std::string position(const std::array<double, 3>& mm) {
  std::ostringstream s;
  s.precision(10);
  s << mm[0] << ',' << mm[1] << ',' << mm[2];
  return s.str();
}

void printVertebraSummary(const cementsph::scene::InjectionRunResult& r, const fs::path& out) {
  const cementsph::scene::InjectionSummary& s = r.summary;
  std::cout << "demo --vertebra: " << s.boneModel << " bone (porosity at the tip "
            << r.engineFigures.at("porosity_at_tip").get<double>() << "), " << s.cementVolumeMl
            << " ml injected, syringe pressure " << s.injectionPressurePa * 1e-6 << " MPa; leakage "
            << s.leakageVolumeMl << " ml at " << s.leakageSites.size() << " site(s)";
  for (const auto& site : s.leakageSites)
    std::cout << "; " << site.volumeMl << " ml at (" << position(site.positionMm) << ") mm from " << site.firstTimeS
              << " s";
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
  cementsph::scene::InjectionRunResult result;
  const int rc = cementsph::app::runInject(inject, &result);
  if (rc != 0 && rc != 3) return rc;
  study::writeVertebraDemoMetrics(result, secondsSince(start), out / "metrics.json");
  printVertebraSummary(result, out);
  return rc;
}

// The three subcommands in turn; false (with *rc their status) when one failed outright. A status 3 (a picture
// failed, its numbers are written) goes on and is reported at the end in *status.
bool runFoamSteps(const DemoOptions& o, const fs::path& phantom, const cementsph::phantom::PhantomInjectionPlan& plan,
                  study::FoamDemoResults& r, int* rc, int* status) {
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
  if (!step(cementsph::app::runInject(inject, &r.inject))) return false;

  std::cerr << "demo 2/4: comparing with the phantom's post-injection CT\n";
  cementsph::app::CompareRequest compare;
  compare.pre = (phantom / "pre.nrrd").string();
  compare.post = (phantom / "post.nrrd").string();
  compare.simulated = (out / "inject" / "simulated_ct.nrrd").string();
  compare.injection = {plan.tipMm[0], plan.tipMm[1], plan.tipMm[2]};
  compare.out = (out / "compare").string();
  if (!step(cementsph::app::runCompare(compare, &r.compare))) return false;

  // The experiment's X-ray sequence has two frames: the pre-injection CT (t = 0) and the registered
  // post-injection CT, taken as the frame at the end of the injection (the simulation's last frame).
  std::cerr << "demo 3/4: X-ray sequences (Fig. 12): the simulation's frames and the post-injection CT's\n";
  cementsph::app::XrayRequest xrayRequest;
  xrayRequest.sequence = {(out / "inject").string()};
  xrayRequest.reference = {(phantom / "pre.nrrd").string(), (out / "compare" / "registered_post.nrrd").string()};
  xrayRequest.referenceTimesS = {0.0, r.inject.summary.simulatedTimeS};
  xrayRequest.drr.threads = o.threads;
  xrayRequest.out = (out / "xray").string();
  return step(cementsph::app::runXray(xrayRequest, &r.xray));
}

int runDemo(const DemoOptions& o) {
  if (o.vertebra) return runVertebraDemo(o);
  const auto start = std::chrono::steady_clock::now();
  const fs::path phantom = fs::path(o.dataDir) / "foam-phantom";
  const cementsph::phantom::PhantomInjectionPlan plan = cementsph::phantom::readInjectionPlan(phantom);
  const fs::path out(o.out);
  study::FoamDemoResults results;
  int rc = 0, status = 0;
  if (!runFoamSteps(o, phantom, plan, results, &rc, &status)) return rc;

  std::cerr << "demo 4/4: summary\n";
  for (const char* picture : {"tip_pressure.png", "injection_pressure.png"}) {
    std::error_code ec;
    fs::copy_file(out / "inject" / picture, out / picture, fs::copy_options::overwrite_existing, ec);
    if (ec) {
      std::cerr << "cementsph demo: picture " << picture << " not copied: " << ec.message() << "\n";
      status = 3;
    }
  }
  results.wallTimeS = secondsSince(start);
  study::writeFoamDemoMetrics(results, out / "metrics.json");
  std::cout << "demo done in " << results.wallTimeS << " s: " << (out / "metrics.json").string() << ", "
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
