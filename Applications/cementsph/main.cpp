// cementsph: the command-line front end. `cementsph --help` lists the subcommands.
#include "CommandRegistry.h"
#include "cementsph/parallel/CaseFarm.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/LibraryMessages.h"
#include "cementsph/provenance/Provenance.h"
#ifdef CEMENTSPH_HAS_RENDERING
#include "cementsph/rendering/RenderBackend.h"
#endif
#include "cementsph/sph/Simulation.h"

#include <omp.h>

#include <csignal>
#include <new>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <map>
#include <streambuf>
#include <stdexcept>

namespace cementsph::app {

namespace {

// --threads N beyond the machine's cores only oversubscribes it (and 100000 threads exhausted the
// process: a segfault), so every subcommand's --threads is capped at the cores; negative is an error.
void capThreadsOption(CLI::App& sub) {
  CLI::Option* threads = sub.get_option_no_throw("--threads");
  if (!threads) return;
  threads->transform(CLI::Validator(
      [](std::string& value) -> std::string {
        long n = 0;
        try {
          std::size_t used = 0;
          n = std::stol(value, &used);
          if (used != value.size()) return "must be a whole number of threads (got '" + value + "')";
        } catch (const std::exception&) {
          return "must be a whole number of threads (got '" + value + "')";
        }
        if (n < 0) return value + " is negative (0: the cores the load average leaves free)";
        value = std::to_string(std::min<long>(n, omp_get_num_procs()));
        return {};
      },
      "", "cap at the cores"));
}

// Every floating-point option of every subcommand takes finite numbers only: CLI11's ranges let NaN through (a
// comparison with NaN is false), and a NaN or infinite radius, threshold or time must never reach the modules
// (`compare --injection-search-radius-mm nan` once wrote a cement volume of 0). A subnormal value (below
// DBL_MIN, 2.2e-308, but not 0) is refused too: no length, time, volume, pressure or viscosity in the units
// the options name comes near it, and it turned into infinities further on that blamed another option
// (`inject --viscosity-pa-s 1e-320`: "no finite time step").
void requireFiniteNumbers(CLI::App& sub) {
  for (CLI::Option* option : sub.get_options()) {
    if (option->get_type_name().find("FLOAT") == std::string::npos) continue;
    option->check(CLI::Validator(
        [](std::string& value) -> std::string {
          char* end = nullptr;
          const double x = std::strtod(value.c_str(), &end);
          if (end != value.c_str() && !std::isfinite(x))
            return "must be a finite number (got '" + value.substr(0, 40) + "')";
          if (end != value.c_str() && x != 0 && std::fabs(x) < DBL_MIN)
            return "'" + value.substr(0, 40) + "' is below 2.2e-308 (a subnormal number) and not 0: no quantity in "
                   "this option's unit is that small; give 0 or a real value";
          return {};
        },
        "", "finite"));
  }
}

// The largest magnitude an option's unit allows, by the unit its name ends in: beyond these no CT, cannula,
// injection or X-ray geometry exists, and 1e308 went on into library code (`compare --closing-radius-mm 1e308`:
// ITK's "Requested region is outside the largest possible region" with a source path; a 300-digit tip printed
// with %f). An option of another unit has no such cap.
struct UnitLimit {
  const char* suffix;
  double limit;
  const char* why;
};
constexpr UnitLimit kUnitLimits[] = {
    {"-mm", 1e6, "1e6 mm (a kilometre), past any CT or X-ray geometry"},
    {"-deg", 1e6, "1e6 degrees"},
    {"-ml", 1e6, "1e6 ml (a cubic metre)"},
    {"-ml-per-s", 1e6, "1e6 ml/s"},
    {"-s", 1e7, "1e7 s (four months; cement sets in minutes)"},
    {"-hu", 1e6, "1e6 HU (CT values lie within -1024 .. 30000)"},
    {"-voxels", 1e3, "1000 voxels (wider than any CT's slab)"},
    {"-mpa", 1e6, "1e6 MPa"},
    {"-pa-s", 1e9, "1e9 Pa.s (a setting cement dough is 1e4-1e5 Pa.s)"}, // not seconds
    {"-m-per-s", 1e6, "1e6 m/s"},                                          // not seconds
};

void requireUnitRanges(CLI::App& sub) {
  for (CLI::Option* option : sub.get_options()) {
    if (option->get_type_name().find("FLOAT") == std::string::npos) continue;
    const std::string name = option->get_name(false, true);
    const UnitLimit* unit = nullptr;
    for (const UnitLimit& u : kUnitLimits) // the longest matching suffix: -ml-per-s before -s
      if (name.size() > std::strlen(u.suffix) && name.compare(name.size() - std::strlen(u.suffix), std::string::npos, u.suffix) == 0 &&
          (!unit || std::strlen(u.suffix) > std::strlen(unit->suffix)))
        unit = &u;
    if (!unit) continue;
    option->check(CLI::Validator(
        [unit](std::string& value) -> std::string {
          char* end = nullptr;
          const double x = std::strtod(value.c_str(), &end);
          if (end != value.c_str() && std::isfinite(x) && std::fabs(x) > unit->limit)
            return "'" + value.substr(0, 40) + "' is beyond " + unit->why + "; check the value and its unit";
          return {};
        },
        "", "in range"));
  }
}

// An option given an empty value ('--shell-mm ""', '--out ""') is refused: CLI11 reads "" as the number 0 or
// an empty path, so the run went on with a value nobody typed (a shell of 0 mm; `inject --out ""` wrote its
// files into the current folder).
void refuseEmptyValues(CLI::App& sub) {
  for (CLI::Option* option : sub.get_options()) {
    if (option->get_type_name().empty()) continue; // a flag: takes no value
    option->check(CLI::Validator(
        [](std::string& value) -> std::string {
          if (value.find_first_not_of(" \t") == std::string::npos) return "is empty: give a value";
          return {};
        },
        "", "not empty"));
  }
}
} // namespace

std::vector<Command>& CommandRegistry::commands() {
  static std::vector<Command> all;
  return all;
}

bool CommandRegistry::add(Command command) {
  commands().push_back(std::move(command));
  return true;
}

} // namespace cementsph::app

namespace {

// OpenMP threads when the user chose none (OMP_NUM_THREADS, or a command's --threads, which overrides
// this): the cores the 1-minute load average leaves free, at least one. Where other programs keep
// cores busy, a full team's barriers wait on descheduled threads: measured on this 2-core machine with
// two other busy processes, the 5 ml injection took 83 s on 2 threads against 10 s on 1.
void chooseDefaultThreads() {
  const int cores = omp_get_num_procs();
  if (const char* fromEnvironment = std::getenv("OMP_NUM_THREADS")) {
    // Capped as --threads is (capThreadsOption).
    if (std::atol(fromEnvironment) > cores) omp_set_num_threads(cores);
    return;
  }
  double load = 0.0;
  if (getloadavg(&load, 1) != 1) return;
  omp_set_num_threads(std::clamp(static_cast<int>(std::lround(cores - load)), 1, cores));
}

// Exit status (README, "Exit status"): 0 done; 1 bad input or options (one line naming which); 2 the run
// failed (out of memory, a file that could not be written: disk full, ...); 3 a picture failed (the
// numbers were written), as the subcommands return themselves.
constexpr int kBadInput = 1, kFailedRun = 2;

// Where --quiet sends a command's own output.
class NullBuffer : public std::streambuf {
protected:
  int overflow(int c) override { return traits_type::not_eof(c); }
  std::streamsize xsputn(const char*, std::streamsize n) override { return n; }
};

// One line: the message with its line breaks turned into spaces (library messages can hold several).
std::string singleLine(const std::string& text) { return cementsph::imaging::oneLine(text); }

// Adds every registered command as a subcommand of `app` (sorted by name) and returns their runners. --quiet on
// every subcommand: a command with its own (inject, phantom, plan: no progress line) keeps it; on the others it
// sets *quiet, which silences what they print but errors (main prints those itself, after the run).
std::map<CLI::App*, cementsph::app::CommandRunner> addSubcommands(CLI::App& app, bool* quiet) {
  using namespace cementsph::app;
  auto& commands = CommandRegistry::commands();
  std::sort(commands.begin(), commands.end(), [](const Command& a, const Command& b) { return a.name < b.name; });
  std::map<CLI::App*, CommandRunner> runners;
  for (const Command& command : commands) {
    CLI::App* sub = app.add_subcommand(command.name, command.summary);
    runners[sub] = command.setup(*sub);
    capThreadsOption(*sub);
    refuseEmptyValues(*sub);
    requireFiniteNumbers(*sub);
    requireUnitRanges(*sub);
    if (!sub->get_option_no_throw("--quiet"))
      sub->add_flag("--quiet", *quiet, "Print nothing but errors (the files are written as usual)");
  }
  return runners;
}

// A parse error as one line naming the option, and where the options are listed; not CLI11's own exit codes
// (105-114).
int reportParseError(const CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  std::string name = "cementsph";
  for (const CLI::App* sub : app.get_subcommands()) name += " " + sub->get_name();
  if (!app.get_subcommands().empty()) {
    std::cerr << name << ": error: " << singleLine(e.what()) << " (see " << name << " --help)\n";
    return kBadInput;
  }
  // No subcommand recognised: name the word that is not one, and list those there are.
  std::string word, names;
  for (int i = 1; i < argc && word.empty(); ++i)
    if (argv[i][0] != '-') word = argv[i];
  for (const auto& command : cementsph::app::CommandRegistry::commands())
    names += (names.empty() ? "" : ", ") + command.name;
  if (!word.empty())
    std::cerr << "cementsph: error: '" << singleLine(word).substr(0, 60) << "' is not a subcommand (the subcommands: "
              << names << "; see cementsph --help)\n";
  else
    std::cerr << "cementsph: error: a subcommand is required (the subcommands: " << names << "; see cementsph --help)\n";
  return kBadInput;
}

// Runs one command: its exit status, or for what it threw, one line on stderr (the command's name first) and the
// status of the failure's kind. --quiet: the command's own output is silenced while it runs; the error line
// comes after, to the real stderr.
int runCommand(const std::string& name, const cementsph::app::CommandRunner& run, bool quiet) {
  const std::string prefix = "cementsph " + name + ": error: ";
  std::streambuf* const out = std::cout.rdbuf();
  std::streambuf* const err = std::cerr.rdbuf();
  NullBuffer nothing; // outlives `restore`
  struct Restore {
    std::streambuf *out, *err;
    void now() const {
      std::cout.rdbuf(out);
      std::cerr.rdbuf(err);
    }
    ~Restore() { now(); }
  } restore{out, err};
  if (quiet) {
    std::cout.rdbuf(&nothing);
    std::cerr.rdbuf(&nothing);
  }
  auto fail = [&](int status, const std::string& message) {
    restore.now();
    std::cerr << prefix << message << "\n";
    return status;
  };
  try {
    return run();
  } catch (const cementsph::parallel::FarmStopped&) { // a worker rank: rank 0 says why
    restore.now();
    return kBadInput;
  } catch (const CLI::ParseError& e) { // a subcommand run by another one (demo: inject, compare)
    return fail(kBadInput, singleLine(e.what()));
  } catch (const std::bad_alloc&) {
    return fail(kFailedRun, "out of memory (a smaller volume, region or particle count needs less)");
  } catch (const cementsph::sph::SimulationError& e) { // unstable, or the cement has nowhere to go
    return fail(kFailedRun, singleLine(e.what()));
  } catch (const cementsph::imaging::OutputError& e) {
    return fail(kFailedRun, singleLine(e.what()));
  } catch (const std::exception& e) {
    return fail(kBadInput, singleLine(e.what()));
  }
}

} // namespace

int main(int argc, char** argv) {
  using namespace cementsph::app;
  // A file over the size limit (ulimit -f) fails the write with EFBIG, reported as a failed run, instead of
  // SIGXFSZ killing the process with a partial file.
  std::signal(SIGXFSZ, SIG_IGN);
  chooseDefaultThreads();
  cementsph::provenance::setCommandLine(argc, argv);
  // Under mpirun every rank runs the command; rank 0 reports the errors (a worker's own reach it through
  // the case farm), so a bad option is one line, not one per rank.
  const bool quietRank = cementsph::parallel::launchedByMpi() && cementsph::parallel::launchedRank() != 0;
  if (quietRank) std::cerr.setstate(std::ios::failbit);
  CLI::App app{"CementSPH: predicts how PMMA bone cement spreads through porous bone (SPH, "
               "Basafa et al. 2013) and checks it against CT.",
               "cementsph"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "cementsph 0.1.0");
  bool verbose = false, quiet = false;
  app.add_flag("--verbose", verbose, "Let GDCM, ITK and VTK print their own warnings and errors to stderr");
  app.fallthrough(); // --verbose also after the subcommand's name
  const std::map<CLI::App*, CommandRunner> runners = addSubcommands(app, &quiet);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return reportParseError(app, e, argc, argv);
  }
  cementsph::imaging::setLibraryMessagesVerbose(verbose);
#ifdef CEMENTSPH_HAS_RENDERING
  // Environment options are checked before any work, not when the first picture is drawn.
  try {
    cementsph::rendering::checkRenderBackendEnvironment();
  } catch (const std::exception& e) {
    std::cerr << "cementsph: error: " << singleLine(e.what()) << "\n";
    return kBadInput;
  }
#endif
  for (const Command& command : CommandRegistry::commands()) {
    CLI::App* sub = app.get_subcommand(command.name);
    if (!sub->parsed()) continue;
    if (quietRank && !command.spreadsOverRanks) return 0; // rank 0 runs this command alone
    return runCommand(command.name, runners.at(sub), quiet);
  }
  return kBadInput;
}
