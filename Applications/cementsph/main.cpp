// cementsph: the command-line front end. `cementsph --help` lists the subcommands.
#include "CommandRegistry.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <map>
#include <stdexcept>

namespace cementsph::app {

std::vector<Command>& CommandRegistry::commands() {
  static std::vector<Command> all;
  return all;
}

bool CommandRegistry::add(Command command) {
  commands().push_back(std::move(command));
  return true;
}

int CommandRegistry::run(const std::string& name, std::vector<std::string> args) {
  for (const auto& command : commands()) {
    if (command.name != name) continue;
    CLI::App sub{command.summary, name};
    const auto runner = command.setup(sub);
    std::reverse(args.begin(), args.end()); // CLI11 takes a vector in reverse order
    sub.parse(args);
    return runner();
  }
  throw std::logic_error("no subcommand '" + name + "'");
}

} // namespace cementsph::app

namespace {

// OpenMP threads when the user chose none (OMP_NUM_THREADS, or a command's --threads, which overrides
// this): the cores the 1-minute load average leaves free, at least one. Where other programs keep
// cores busy, a full team's barriers wait on descheduled threads: measured on this 2-core machine with
// two other busy processes, the 5 ml injection took 83 s on 2 threads against 10 s on 1.
void chooseDefaultThreads() {
  if (std::getenv("OMP_NUM_THREADS")) return;
  double load = 0.0;
  if (getloadavg(&load, 1) != 1) return;
  const int cores = omp_get_num_procs();
  omp_set_num_threads(std::clamp(static_cast<int>(std::lround(cores - load)), 1, cores));
}

} // namespace

int main(int argc, char** argv) {
  using namespace cementsph::app;
  chooseDefaultThreads();
  CLI::App app{"CementSPH: predicts how PMMA bone cement spreads through porous bone (SPH, "
               "Basafa et al. 2013) and checks it against CT.",
               "cementsph"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "cementsph 0.1.0");

  auto& commands = CommandRegistry::commands();
  std::sort(commands.begin(), commands.end(),
            [](const Command& a, const Command& b) { return a.name < b.name; });
  std::map<CLI::App*, CommandRunner> runners;
  for (const Command& command : commands) {
    CLI::App* sub = app.add_subcommand(command.name, command.summary);
    runners[sub] = command.setup(*sub);
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  for (auto& [sub, run] : runners) {
    if (!sub->parsed()) continue;
    try {
      return run();
    } catch (const std::exception& e) {
      std::cerr << "cementsph " << sub->get_name() << ": error: " << e.what() << "\n";
      return 1;
    }
  }
  return 1;
}
