// cementsph darcy: the paper's Darcy permeability protocol (Figs. 1, 4, 5) over a sweep of porosities,
// spacings and viscosities. Writes DIR/permeability.csv (and DIR/permeability.png). A thin layer over
// CementSPH::SPH's DarcyBenchmark.h (the runs) and DarcyTable.h (the CSV).
#include "CommandRegistry.h"
#include "OutputFiles.h"

#include "cementsph/sph/DarcyBenchmark.h"
#include "cementsph/sph/DarcyTable.h"
#include "cementsph/sph/Presets.h"
#include "cementsph/sph/Simulation.h"
#include "cementsph/scene/SceneSettings.h"
#include "cementsph/study/DarcyPlot.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace {

using namespace cementsph;
using namespace cementsph::sph;

struct DarcyOptions {
  std::vector<double> porosities{0.5, 0.6, 0.7, 0.8, 0.9};
  std::vector<double> spacingsMm{0.5, 1.0};
  std::vector<double> viscositiesPaS{10.0, 100.0};
  std::vector<double> bodyForces; // m/s^2; empty: the default sweep
  std::string out = "darcy-out";
  std::string preset = "default";
  std::string integrator, viscosityModel;
  double hOverD = 0, dragCoefficient = 0, soundSpeed = 0, timeStep = 0;
  int lattice = 25, threads = 0;
  std::uint64_t seed = 1;
  double tolerance = 1e-2;
  std::uint64_t maxSteps = 400000;
  bool clampTimeStep = false, noPlot = false;
};

void requireAll(const std::vector<double>& v, const char* what, bool (*ok)(double)) {
  if (v.empty()) throw std::invalid_argument(std::string(what) + ": at least one value is needed");
  for (double x : v)
    if (!std::isfinite(x) || !ok(x)) {
      std::ostringstream s;
      s << what << ": value " << x << " is out of range";
      throw std::invalid_argument(s.str());
    }
}

void requireWithin(double x, double lo, double hi, const char* what, const char* why) {
  if (!(x >= lo && x <= hi)) {
    std::ostringstream s;
    s << what << ": " << x << " is outside " << lo << ".." << hi << " (" << why << ")";
    throw std::invalid_argument(s.str());
  }
}

void checkOptions(const DarcyOptions& o) {
  // Porosity 1 leaves no solid: the permeability is infinite, not a number for the CSV.
  requireAll(o.porosities, "--porosities", [](double p) { return p > 0 && p < 1; });
  requireAll(o.spacingsMm, "--spacings-mm", [](double d) { return d >= 1e-3 && d <= 100; });
  requireAll(o.viscositiesPaS, "--viscosities-pa-s", [](double m) { return m > 0 && m <= 1e7; });
  if (!o.bodyForces.empty()) {
    requireAll(o.bodyForces, "--body-forces-m-per-s2", [](double f) { return f > 0 && f <= 1e6; });
    // The permeability is the slope of flow against force: one force gives no slope.
    if (o.bodyForces.size() < 2)
      throw std::invalid_argument("--body-forces-m-per-s2: give at least two body forces (the permeability is the "
                                  "slope of the mean velocity against the force), or leave it out for the default sweep");
  }
  // Each value is a full permeability run (seconds to minutes): 1e5 porosities ran past any wait, as study's sweeps.
  constexpr std::size_t kMaxSweep = 100;
  for (const auto& [option, count] : {std::pair<const char*, std::size_t>{"--porosities", o.porosities.size()},
                                      {"--spacings-mm", o.spacingsMm.size()},
                                      {"--viscosities-pa-s", o.viscositiesPaS.size()},
                                      {"--body-forces-m-per-s2", o.bodyForces.size()}})
    if (count > kMaxSweep)
      throw std::invalid_argument(std::string(option) + ": " + std::to_string(count) + " values; at most " +
                                  std::to_string(kMaxSweep) + " (each is a full permeability run)");
  if (o.lattice < 4) throw std::invalid_argument("--lattice: at least 4 particles per side");
  requireWithin(o.lattice, 4, 200, "--lattice", "200^3 particles is the most this benchmark runs");
  // A tolerance of 0 is never met: every body force would run to the step cap.
  requireWithin(o.tolerance, 1e-5, 0.5, "--steady-tolerance", "relative change between windows");
  requireWithin(double(o.maxSteps), 1, 1e7, "--max-steps-per-force", "steps for one body force");
  // Below a picosecond the step count of a run overflows; the stability limits refuse the large end.
  if (o.timeStep != 0) requireWithin(o.timeStep, 1e-12, 10, "--time-step-s", "a fixed time step in seconds");
  const std::pair<double, const char*> positive[] = {
      {o.hOverD, "--h-over-d"}, {o.dragCoefficient, "--drag-coefficient"}, {o.soundSpeed, "--sound-speed-m-per-s"}};
  for (const auto& [x, option] : positive)
    if (!std::isfinite(x) || x < 0) throw std::invalid_argument(std::string(option) + ": must be a finite number > 0");
}

// The preset with the options' model settings over it.
ModelPreset darcyPreset(const DarcyOptions& o) {
  ModelPreset preset = modelPreset(o.preset);
  ModelParameters& model = preset.model;
  // The parsers' lines name the value and the choices; the option is named here, where it is known.
  try {
    if (!o.integrator.empty()) model.integrator = parseIntegrator(o.integrator);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--integrator: ") + e.what());
  }
  try {
    if (!o.viscosityModel.empty()) model.viscosityModel = parseViscosityModel(o.viscosityModel);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--viscosity-model: ") + e.what());
  }
  if (o.hOverD > 0) preset.hOverD = o.hOverD;
  if (o.dragCoefficient > 0) model.dragCoefficient = o.dragCoefficient;
  if (o.soundSpeed > 0) model.soundSpeed = o.soundSpeed;
  if (o.timeStep > 0) model.fixedTimeStep = o.timeStep;
  model.stepLimitPolicy = o.clampTimeStep ? StepLimitPolicy::Clamp : StepLimitPolicy::Refuse;
  return preset;
}

// The lattice is a periodic box n d wide, and the neighbour search needs it wider than twice the neighbour-list
// radius 2h (1 + skin/2) with h = (h/d) d (Simulation's start check): n > 4 (h/d) (1 + skin/2). Checked here
// so that the line names --lattice and its smallest value, not the simulation's box.
void checkLatticeFitsNeighbourRadius(int lattice, const ModelPreset& preset) {
  const double narrowest = 4.0 * preset.hOverD * (1.0 + 0.5 * preset.model.neighbourSkin);
  if (double(lattice) > narrowest) return;
  const double smallest = std::floor(narrowest) + 1.0;
  std::ostringstream s;
  s << "--lattice: " << lattice << " particles per side make a periodic box narrower than twice the neighbour "
    << "radius at h/d " << preset.hOverD << "; use --lattice " << smallest << " or more (or a smaller --h-over-d)";
  throw std::invalid_argument(s.str());
}

void printCase(std::size_t done, std::size_t total, double porosity, double spacingMm, double viscosityPaS,
               const DarcyResult& r) {
  std::cerr << "[" << done << "/" << total << "] porosity " << porosity << ", spacing " << spacingMm << " mm, "
            << viscosityPaS << " Pa.s: k/d^2 " << std::setprecision(4) << r.dimensionlessPermeability << ", R^2 "
            << std::setprecision(6) << r.r2 << ", " << r.steps << " steps, " << std::setprecision(3) << r.wallSeconds
            << " s" << (r.converged ? "" : "  (NOT converged: raise the step cap)") << "\n";
}

// The model options the user gave, for a run the simulation refuses ("no finite time step" for --drag-coefficient
// 1e308; "time step 5 s exceeds the ... stability limit" for --time-step-s 5): the line names them.
std::string givenModelOptions(const DarcyOptions& o) {
  std::ostringstream s;
  const std::pair<double, const char*> model[] = {{o.timeStep, "--time-step-s"},
                                                  {o.dragCoefficient, "--drag-coefficient"},
                                                  {o.soundSpeed, "--sound-speed-m-per-s"},
                                                  {o.hOverD, "--h-over-d"}};
  for (const auto& [x, option] : model)
    if (x > 0) s << (s.tellp() > 0 ? ", " : "") << option << " " << x;
  return s.str();
}

DarcyResult runCase(DarcyBenchmark& bench, const DarcyCase& c, const DarcyOptions& o) {
  try {
    return bench.run(c, [](const std::string& line) { std::cerr << "  " << line << "\n"; });
  } catch (const cementsph::sph::SimulationError& e) {
    const std::string given = givenModelOptions(o);
    if (given.empty()) throw;
    throw std::invalid_argument(given + ": " + e.what() + " (porosity " + scene::exactNumber(c.porosity) +
                                ", spacing " + scene::exactNumber(c.spacing * 1e3) + " mm)");
  }
}

// A failed sweep's files: the table (and a folder this run made, when empty).
void removeOutputs(const std::string& out, const std::filesystem::path& csvPath, bool outExisted) {
  std::error_code ec;
  std::filesystem::remove(csvPath, ec);
  if (!outExisted && std::filesystem::is_empty(out, ec)) std::filesystem::remove(out, ec);
}

int runDarcy(const DarcyOptions& o) {
  checkOptions(o);
  if (o.threads > 0) omp_set_num_threads(o.threads);
  const ModelPreset preset = darcyPreset(o);
  checkLatticeFitsNeighbourRadius(o.lattice, preset);
  const ModelParameters& model = preset.model;
  SteadyStateCriteria criteria;
  criteria.relativeTolerance = o.tolerance;
  criteria.maxSteps = o.maxSteps;
  std::cerr << "cementsph darcy: preset " << preset.name << " (h/d " << preset.hOverD << ", "
            << toString(model.integrator) << ", Cf " << model.dragCoefficient << "), " << o.lattice << "^3 lattice, "
            << omp_get_max_threads() << " threads\n";
  const bool outExisted = std::filesystem::exists(o.out);
  std::vector<DarcyResult> results;
  // The CSV is rewritten (atomically) after every case, so a long sweep keeps what it has done.
  const std::filesystem::path csvPath = std::filesystem::path(o.out) / "permeability.csv";
  const DarcyTableModel tableModel{preset.hOverD, model.dragCoefficient, toString(model.integrator)};
  DarcyBenchmark bench(model, preset.hOverD, criteria);
  const std::size_t total = o.porosities.size() * o.spacingsMm.size() * o.viscositiesPaS.size();
  for (double spacing : o.spacingsMm)
    for (double mu : o.viscositiesPaS)
      for (double phi : o.porosities) {
        DarcyCase c;
        c.latticeSize = o.lattice;
        c.spacing = spacing * 1e-3;
        c.porosity = phi;
        c.viscosity = mu;
        c.seed = o.seed;
        c.bodyForces = o.bodyForces;
        results.push_back(runCase(bench, c, o));
        printCase(results.size(), total, phi, spacing, mu, results.back());
        std::filesystem::create_directories(o.out); // after the first run: one the simulation refuses leaves none
        app::writeFileAtomically(csvPath, darcyPermeabilityCsv(results, tableModel));
      }
  // A table of runs none of which converged holds no permeability: a failed run, and nothing is left behind.
  if (std::none_of(results.begin(), results.end(), [](const DarcyResult& r) { return r.converged; })) {
    removeOutputs(o.out, csvPath, outExisted);
    throw cementsph::sph::SimulationError("none of the " + std::to_string(results.size()) +
                                          " runs converged within --max-steps-per-force " + std::to_string(o.maxSteps) +
                                          ": raise it (nothing written)");
  }
  std::cout << "wrote " << csvPath.string() << "\n";
  if (!o.noPlot) {
    const std::filesystem::path png = std::filesystem::path(o.out) / "permeability.png";
    cementsph::study::writeDarcyPlot(results, png);
    std::cout << "wrote " << png.string() << "\n";
  }
  // A run that did not converge is a failed run (status 2, README "Exit status"); the CSV keeps its row (converged
  // 0). Thrown, so that main prints the one line even under --quiet (a plain return 2 printed nothing there).
  std::size_t notConverged = 0;
  for (const DarcyResult& r : results) notConverged += r.converged ? 0 : 1;
  if (notConverged > 0)
    throw cementsph::sph::SimulationError(std::to_string(notConverged) + " of " + std::to_string(results.size()) +
                                          " runs did not converge within --max-steps-per-force " +
                                          std::to_string(o.maxSteps) + " (converged 0 in permeability.csv): raise it");
  return 0;
}

app::CommandRunner setupDarcy(CLI::App& sub) {
  auto o = std::make_shared<DarcyOptions>();
  sub.add_option("--porosities", o->porosities, "porosities to simulate (0 < p <= 1)")->delimiter(',')
      ->capture_default_str();
  sub.add_option("--spacings-mm", o->spacingsMm, "particle spacings d [mm]")->delimiter(',')->capture_default_str();
  sub.add_option("--viscosities-pa-s", o->viscositiesPaS, "viscosities [Pa.s]")->delimiter(',')->capture_default_str();
  sub.add_option("--body-forces-m-per-s2", o->bodyForces,
                 "body forces [m/s^2] (default: 4 values up to 2e-3 cs^2/d, the linear range)")->delimiter(',');
  sub.add_option("--out", o->out, "output folder")->capture_default_str();
  sub.add_option("--preset", o->preset, "model preset: default or paper")->capture_default_str();
  sub.add_option("--integrator", o->integrator, "central-difference (paper), explicit or overdamped");
  sub.add_option("--viscosity-model", o->viscosityModel, "drag (paper Eq. 9), morris (Eq. 7) or none");
  sub.add_option("--h-over-d", o->hOverD, "smoothing length over particle spacing (paper: 0.5)");
  sub.add_option("--drag-coefficient", o->dragCoefficient, "Cf of Eq. 9");
  sub.add_option("--sound-speed-m-per-s", o->soundSpeed, "cs of Eq. 6 [m/s]");
  sub.add_option("--time-step-s", o->timeStep, "fixed time step [s] (default: chosen from the stability limits)");
  sub.add_flag("--clamp-time-step", o->clampTimeStep, "clamp a fixed time step above the stability limit instead of refusing it");
  sub.add_option("--lattice", o->lattice, "particles per side of the cubic lattice")->capture_default_str();
  sub.add_option("--seed", o->seed, "random seed for the fixed sites")->capture_default_str();
  sub.add_option("--steady-tolerance", o->tolerance, "relative change between windows that counts as steady")
      ->capture_default_str();
  sub.add_option("--max-steps-per-force", o->maxSteps, "step cap for one body force (not converged past it)")
      ->capture_default_str();
  sub.add_option("--threads", o->threads, "OpenMP threads (0: the cores the load average leaves free)");
  sub.add_flag("--no-plot", o->noPlot, "write the CSV only");
  return [o] { return runDarcy(*o); };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(darcy, "darcy",
                           "Darcy permeability of random porous media (paper Figs. 4-5): permeability.csv and .png",
                           setupDarcy)
