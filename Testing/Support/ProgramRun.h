// Running a program from a test as a user would, with its exit status and both output streams.
// Arguments are passed as a list and shell-quoted here, so paths with spaces or quotes are safe.
#pragma once

#include <string>
#include <vector>

namespace cementsph::testing {

struct ProgramRun {
  int exitCode = -1; // the program's exit status; 128 + signal number when a signal ended it
  std::string out, err;
};

ProgramRun runProgram(const std::string& program, const std::vector<std::string>& args);

// The same with the arguments as one line, split at white space (for arguments without spaces).
ProgramRun runProgram(const std::string& program, const std::string& argumentLine);

} // namespace cementsph::testing
