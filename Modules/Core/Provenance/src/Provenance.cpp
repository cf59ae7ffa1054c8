#include "cementsph/provenance/Provenance.h"

namespace cementsph::provenance {

namespace detail {
extern const char* const kGitRevision; // Revision.cpp, generated at build time
}

namespace {

std::string& storedCommandLine() {
  static std::string line;
  return line;
}

// A word as a shell would need it to be typed again: plain, or in single quotes.
std::string quoted(const std::string& word) {
  if (!word.empty() && word.find_first_of(" \t\n'\"\\$`*?;&|<>()") == std::string::npos) return word;
  std::string q = "'";
  for (char c : word) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

} // namespace

void setCommandLine(int argc, const char* const* argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) line += (i ? " " : "") + quoted(argv[i] ? argv[i] : "");
  storedCommandLine() = line;
}

const std::string& commandLine() { return storedCommandLine(); }
std::string version() { return CEMENTSPH_VERSION; }
std::string gitRevision() { return detail::kGitRevision; }

nlohmann::json toJson() {
  return {{"program", "cementsph"}, {"version", version()}, {"git_revision", gitRevision()},
          {"command_line", commandLine()}};
}

} // namespace cementsph::provenance
