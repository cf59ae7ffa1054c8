// What made an output file: the program, its version, the git revision it was built from and the command
// line, as {"program", "version", "git_revision", "command_line"} in every metrics.json, plan.json and
// study.json, so that a figure can be traced to the code and the call that produced it.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace cementsph::provenance {

// Records the command line (main() calls it once; library users may leave it empty).
void setCommandLine(int argc, const char* const* argv);
const std::string& commandLine(); // words joined by spaces, a word with a space or quote in single quotes
std::string version();            // the project's version (CMake's PROJECT_VERSION)
std::string gitRevision();        // 12 hex digits, "-dirty" for a tree with uncommitted changes, or "unknown"
nlohmann::json toJson();

} // namespace cementsph::provenance
