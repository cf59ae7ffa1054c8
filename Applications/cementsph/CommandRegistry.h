// The `cementsph` program is one binary with subcommands (as `git log`, `plastimatch drr`).
// Each subcommand lives in its own <Name>Command.cpp, is a thin layer over the modules, and
// registers itself here with CEMENTSPH_REGISTER_COMMAND, so adding a command touches no shared file.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace cementsph::app {

// A subcommand declares its options on `sub` and returns the function that runs it.
// The runner returns the process exit code; it throws cementsph::app::UsageError (or any
// std::exception) for bad input, which main() turns into one line on stderr and a non-zero exit.
using CommandRunner = std::function<int()>;
using CommandSetup = std::function<CommandRunner(CLI::App& sub)>;

struct Command {
  std::string name;
  std::string summary;
  CommandSetup setup;
  // Whether every rank of an MPI job takes part (study, plan: Modules/Parallel/CaseFarm). Any other
  // command run under mpirun runs on rank 0 alone; the other ranks leave at once, so that N copies never
  // write the same files.
  bool spreadsOverRanks = false;
};

class CommandRegistry {
public:
  static std::vector<Command>& commands();
  static bool add(Command command);
  // No command runs another through argv strings: the ones others need have typed entry points
  // (CommandRequests.h).
};

} // namespace cementsph::app

#define CEMENTSPH_REGISTER_COMMAND(IDENT, NAME, SUMMARY, SETUP)                                    \
  namespace {                                                                                      \
  [[maybe_unused]] const bool registered_##IDENT =                                                 \
      ::cementsph::app::CommandRegistry::add({NAME, SUMMARY, SETUP});                              \
  }

// The same for a command whose cases are spread over the ranks of an MPI job.
#define CEMENTSPH_REGISTER_COMMAND_OVER_RANKS(IDENT, NAME, SUMMARY, SETUP)                         \
  namespace {                                                                                      \
  [[maybe_unused]] const bool registered_##IDENT =                                                 \
      ::cementsph::app::CommandRegistry::add({NAME, SUMMARY, SETUP, true});                        \
  }
