// cementsph demo: the whole product on bundled data, in seconds. The foam phantom pair of
// Data/foam-phantom (made by `cementsph phantom`), an injection with the paper's plan (its scene preset,
// with the volume, rate, viscosity and tip the phantom's post scan was made with, read from truth.json),
// then the comparison against the phantom's post-injection CT (registration, segmentation, surfaces,
// metrics, pictures) and the tip-pressure plot. It runs the `inject` and `compare` subcommands
// themselves, so the demo is exactly what a user gets from them.
#include "CommandRegistry.h"

#include "cementsph/rendering/TipPressurePlot.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace {

namespace fs = std::filesystem;
using cementsph::app::CommandRegistry;

struct DemoOptions {
  std::string dataDir = CEMENTSPH_DATA_DIR;
  std::string out = "out/demo";
  int threads = 0;
};

// Runs a registered subcommand with the given arguments, as if typed after `cementsph NAME`.
int runSubcommand(const std::string& name, std::vector<std::string> args) {
  for (const auto& command : CommandRegistry::commands()) {
    if (command.name != name) continue;
    CLI::App sub{command.summary, name};
    const auto runner = command.setup(sub);
    std::reverse(args.begin(), args.end()); // CLI11 takes a vector in reverse order
    sub.parse(args);
    return runner();
  }
  throw std::logic_error("demo: no subcommand '" + name + "'");
}

std::string vec3(const nlohmann::json& v) {
  std::ostringstream s;
  s.precision(10);
  s << v.at(0).get<double>() << ',' << v.at(1).get<double>() << ',' << v.at(2).get<double>();
  return s.str();
}

int runDemo(const DemoOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path phantom = fs::path(o.dataDir) / "foam-phantom";
  const fs::path truthPath = phantom / "truth.json";
  std::ifstream truthFile(truthPath);
  if (!truthFile) throw std::runtime_error(truthPath.string() + ": cannot read the bundled phantom (use --data-dir)");
  const nlohmann::json truth = nlohmann::json::parse(truthFile);
  const nlohmann::json& plan = truth.at("injection");
  const std::string tip = vec3(plan.at("tip_mm"));
  const fs::path out(o.out);
  const std::string threads = std::to_string(o.threads);

  std::cerr << "demo 1/3: injecting " << plan.at("volume_ml").get<double>() << " ml at "
            << plan.at("flow_rate_ml_per_s").get<double>() << " ml/s, " << plan.at("viscosity_pa_s").get<double>()
            << " Pa.s into the foam phantom (paper's plan)\n";
  int rc = runSubcommand("inject", {"--ct", (phantom / "pre.nrrd").string(), "--scene",
                                    (fs::path(o.dataDir) / "scenes" / "paper.json").string(), "--tip-mm", tip,
                                    "--volume-ml", std::to_string(plan.at("volume_ml").get<double>()),
                                    "--flow-rate-ml-per-s", std::to_string(plan.at("flow_rate_ml_per_s").get<double>()),
                                    "--viscosity-pa-s", std::to_string(plan.at("viscosity_pa_s").get<double>()),
                                    "--threads", threads, "--out", (out / "inject").string()});
  if (rc != 0) return rc;

  std::cerr << "demo 2/3: comparing with the phantom's post-injection CT\n";
  rc = runSubcommand("compare", {"--pre", (phantom / "pre.nrrd").string(), "--post", (phantom / "post.nrrd").string(),
                                 "--simulated", (out / "inject" / "simulated_ct.nrrd").string(),
                                 "--injection-point-mm", tip, "--out", (out / "compare").string()});
  if (rc != 0) return rc;

  std::cerr << "demo 3/3: tip pressure plot\n";
  cementsph::rendering::writeTipPressurePlot(out / "inject" / "tip_pressure.csv", out / "tip_pressure.png");
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "demo done in " << wall << " s: " << (out / "compare" / "metrics.json").string() << ", "
            << (out / "compare" / "surfaces.png").string() << ", " << (out / "compare" / "slices.png").string()
            << ", " << (out / "tip_pressure.png").string() << "; particles for ParaView: "
            << (out / "inject" / "particles.pvd").string() << "\n";
  return 0;
}

cementsph::app::CommandRunner setupDemo(CLI::App& sub) {
  auto o = std::make_shared<DemoOptions>();
  sub.add_option("--out", o->out, "output folder (inject/, compare/, tip_pressure.png)")->capture_default_str();
  sub.add_option("--data-dir", o->dataDir, "folder holding foam-phantom/ and scenes/")->capture_default_str();
  sub.add_option("--threads", o->threads, "OpenMP threads for the injection (0: all cores)");
  return [o] { return runDemo(*o); };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(demo, "demo",
                           "Bundled foam phantom -> injection (paper's plan) -> comparison with its post CT, pictures",
                           setupDemo)
