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
#include <cctype>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <streambuf>
#include <stdexcept>

namespace cementsph::app {

namespace {

// --threads N beyond the machine's cores only oversubscribes it (and 100000 threads exhausted the
// process: a segfault), so every subcommand's --threads is capped at the cores, and the cap is said in one
// line on stderr (threadsCapNote, printed unless --quiet) rather than silently; negative is an error.
std::string& threadsCapNote() {
  static std::string note;
  return note;
}

void capThreadsOption(CLI::App& sub) {
  CLI::Option* threads = sub.get_option_no_throw("--threads");
  if (!threads) return;
  threads->transform(CLI::Validator(
      [](std::string& value) -> std::string {
        long n = 0;
        try {
          std::size_t used = 0;
          n = std::stol(value, &used);
          if (used != value.size()) return "must be a whole number of threads (got '" + value.substr(0, 40) + "')";
        } catch (const std::exception&) {
          return "must be a whole number of threads (got '" + value.substr(0, 40) + "')";
        }
        if (n < 0) return value + " is negative (0: the cores the load average leaves free)";
        const long cores = omp_get_num_procs();
        if (n > cores)
          threadsCapNote() = "--threads " + value + " is more than this machine's " + std::to_string(cores) +
                             " cores; using " + std::to_string(cores);
        value = std::to_string(std::min(n, cores));
        return {};
      },
      "", "cap at the cores"));
}

// Numbers are read in decimal only. CLI11 reads an integer option's '010' as octal (`plan --starts 010` ran 8
// starts) and '0x10' as hexadecimal, and strtod takes '0x10' and '0x1p3' for a floating-point one (16 and 8): a
// value nobody meant, which then failed further on naming another option or a scene key (issue 21's corpus:
// `--volume-ml 0x10` as "16 ml to inject"). Refused, naming the option (CLI11 puts its name first).
std::string nonDecimalProblem(const std::string& value, bool integer, bool isUnsigned) {
  std::size_t i = value.find_first_not_of(" \t");
  if (i == std::string::npos) return {};
  // An unsigned option read '-1' as 2^64 - 1 (`phantom --seed -1` recorded seed 18446744073709551615).
  if (isUnsigned && value[i] == '-')
    return "'" + value.substr(0, 40) + "' is negative: give a whole number, 0 or more";
  if (value[i] == '+' || value[i] == '-') ++i;
  if (i + 1 < value.size() && value[i] == '0' && std::strchr("xXbBoO", value[i + 1]))
    return "'" + value.substr(0, 40) + "' is not a decimal number: write the number in decimal";
  if (integer && i + 1 < value.size() && value[i] == '0' && std::isdigit(static_cast<unsigned char>(value[i + 1])))
    return "'" + value.substr(0, 40) + "' starts with 0, which would read it as octal: write it without the leading 0";
  // Past 64 bits the conversion saturates silently (`--seed 18446744073709551616` ran with 2^64 - 1).
  errno = 0;
  if (isUnsigned) (void)std::strtoull(value.c_str(), nullptr, 10);
  else if (integer) (void)std::strtoll(value.c_str(), nullptr, 10);
  if (integer && errno == ERANGE) return "'" + value.substr(0, 40) + "' is too large for a whole number of 64 bits";
  return {};
}

void requireDecimalNumbers(CLI::App& sub) {
  for (CLI::Option* option : sub.get_options()) {
    const std::string type = option->get_type_name();
    const bool floating = type.find("FLOAT") != std::string::npos;
    if (!floating && type.find("INT") == std::string::npos) continue;
    const bool isUnsigned = type.find("UINT") != std::string::npos;
    option->check(CLI::Validator(
        [floating, isUnsigned](std::string& value) { return nonDecimalProblem(value, !floating, isUnsigned); }, "",
        "decimal"));
  }
}

// --out is a folder for every subcommand: one that is a file, a symbolic link to nothing, or lies under a file
// is refused before any work (`plan --out FILE` ran its trajectory check and printed a warning first, then
// "filesystem error: cannot create directories: Not a directory [...]").
std::string outputFolderProblem(const std::string& value) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path out(value);
  const std::string shown = value.size() > 120 ? value.substr(0, 55) + "..." + value.substr(value.size() - 55) : value;
  if (fs::is_symlink(fs::symlink_status(out, ec)) && !fs::exists(out, ec))
    return shown + " is a symbolic link to nothing: give a folder, or remove the link";
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    return shown + " exists and is not a folder: give a folder (it is created when missing)";
  for (fs::path p = out.parent_path(); !p.empty() && p != p.parent_path(); p = p.parent_path())
    if (fs::exists(p, ec)) {
      if (!fs::is_directory(p, ec)) return shown + " lies under " + p.string().substr(0, 120) + ", a file: give a folder";
      break;
    }
  return {};
}

void checkOutputFolderOption(CLI::App& sub) {
  if (CLI::Option* out = sub.get_option_no_throw("--out"))
    out->check(CLI::Validator([](std::string& value) { return outputFolderProblem(value); }, "", "a folder"));
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

// One line: the message with its line breaks turned into spaces (library messages can hold several), and any
// word over 120 characters (a path or a value as given: the corpus of issue 21 had 50 MB scene values and 4 kB
// paths) shortened to its two ends, so the line stays one a person reads.
std::string singleLine(const std::string& text) {
  const std::string line = cementsph::imaging::oneLine(text);
  constexpr std::size_t kLongWord = 120, kKept = 55;
  std::string shown;
  std::size_t start = 0;
  while (start < line.size()) {
    const std::size_t space = line.find(' ', start);
    const std::size_t end = space == std::string::npos ? line.size() : space + 1;
    const std::string word = line.substr(start, end - start);
    shown += word.size() > kLongWord ? word.substr(0, kKept) + "..." + word.substr(word.size() - kKept) : word;
    start = end;
  }
  return shown;
}

// CLI11's "--volume-ml: At Most 1 required but received 2" (an option given twice) in words.
std::string countErrorLine(const std::string& what) {
  for (const std::string bound : {"At Most ", "At least "}) {
    const std::size_t at = what.find(": " + bound), received = what.find(" required but received ");
    if (at == std::string::npos || received == std::string::npos || received < at) continue;
    const std::string option = what.substr(0, at), wanted = what.substr(at + 2 + bound.size(), received - at - 2 - bound.size());
    const std::string got = what.substr(received + std::strlen(" required but received "));
    if (bound == "At Most " && wanted == "1")
      return option + ": takes one value but was given " + got + " (the option twice?): give it once";
    return option + ": takes " + wanted + " values but was given " + got + ": give " + wanted;
  }
  return what;
}

// CLI11's "Could not convert: --starts = 1_0" as a line a person reads.
std::string parseErrorLine(const CLI::ParseError& e) {
  const std::string what = countErrorLine(singleLine(e.what())), head = "Could not convert: ";
  const std::size_t equals = what.find(" = ");
  if (what.rfind(head, 0) != 0 || equals == std::string::npos) return what;
  const std::string value = what.substr(equals + 3);
  return what.substr(head.size(), equals - head.size()) + ": '" + value.substr(0, 40) + (value.size() > 40 ? "..." : "") +
         "' is not a number of the kind this option takes (a whole number, or a decimal one)";
}

// What a command prints on stderr while it runs, passed through line by line, except its warnings
// ("...: warning: ..."), which are held: printed after a run that succeeds, dropped (printed before the error
// line under --verbose) when it fails, so that a failed run's stderr is its one error line (`plan --out FILE`
// printed the trajectory warning, then the error).
class HoldWarnings : public std::streambuf {
public:
  explicit HoldWarnings(std::streambuf* real) : real_(real) {}
  // The held warnings, and any unfinished line.
  void release() {
    const std::lock_guard<std::mutex> lock(mutex_);
    endLine();
    real_->sputn(held_.data(), std::streamsize(held_.size()));
    held_.clear();
    real_->pubsync();
  }
  void drop() {
    const std::lock_guard<std::mutex> lock(mutex_);
    held_.clear(), line_.clear();
  }

protected:
  int overflow(int c) override {
    if (c == traits_type::eof()) return traits_type::not_eof(c);
    // std::cerr may be written from another thread (a library's warning on the snapshot writer's thread).
    const std::lock_guard<std::mutex> lock(mutex_);
    line_.push_back(char(c));
    if (c == '\n' || c == '\r') endLine();
    return c;
  }
  int sync() override { return real_->pubsync(); }

private:
  void endLine() {
    if (line_.find(": warning: ") != std::string::npos) held_ += line_;
    else real_->sputn(line_.data(), std::streamsize(line_.size()));
    line_.clear();
  }
  std::streambuf* real_;
  std::mutex mutex_;
  std::string line_, held_;
};

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
    requireDecimalNumbers(*sub);
    checkOutputFolderOption(*sub);
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
    std::cerr << name << ": error: " << parseErrorLine(e) << " (see " << name << " --help)\n";
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
int runCommand(const std::string& name, const cementsph::app::CommandRunner& run, bool quiet, bool verbose) {
  const std::string prefix = "cementsph " + name + ": error: ";
  std::streambuf* const out = std::cout.rdbuf();
  std::streambuf* const err = std::cerr.rdbuf();
  NullBuffer nothing;       // outlives `restore`
  HoldWarnings hold(err);   // the same
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
  } else {
    std::cerr.rdbuf(&hold);
  }
  auto fail = [&](int status, const std::string& message) {
    if (verbose) hold.release();
    else hold.drop();
    restore.now();
    std::cerr << prefix << message << "\n";
    return status;
  };
  try {
    const int status = run();
    hold.release();
    return status;
  } catch (const cementsph::parallel::FarmStopped&) { // a worker rank: rank 0 says why
    hold.drop();
    restore.now();
    return kBadInput;
  } catch (const CLI::ParseError& e) { // a subcommand run by another one (demo: inject, compare)
    return fail(kBadInput, parseErrorLine(e));
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

// The --threads cap's note (capThreadsOption), unless the subcommand was given --quiet.
void printThreadsCapNote(const CLI::App& sub, bool quiet) {
  const CLI::Option* quietOption = sub.get_option_no_throw("--quiet");
  const std::string& note = cementsph::app::threadsCapNote();
  if (note.empty() || quiet || (quietOption && quietOption->count() > 0)) return;
  std::cerr << "cementsph " << sub.get_name() << ": note: " << note << "\n";
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
    printThreadsCapNote(*sub, quiet);
    return runCommand(command.name, runners.at(sub), quiet, verbose);
  }
  return kBadInput;
}
