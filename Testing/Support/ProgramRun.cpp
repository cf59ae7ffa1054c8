#include "ProgramRun.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <sys/wait.h>

namespace cementsph::testing {

namespace {

std::string shellQuoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string readAndRemove(const std::filesystem::path& p) {
  std::string text;
  {
    std::ifstream in(p, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::error_code ec;
  std::filesystem::remove(p, ec);
  return text;
}

} // namespace

ProgramRun runProgram(const std::string& program, const std::vector<std::string>& args) {
  // Unique capture files, so tests running in parallel (ctest -j) never share them.
  const auto stem = std::filesystem::temp_directory_path() /
                    ("cementsph-run-" + std::to_string(std::random_device{}()) + "-" + std::to_string(std::rand()));
  const auto outPath = stem.string() + ".out", errPath = stem.string() + ".err";
  std::string command = shellQuoted(program);
  for (const std::string& a : args) command += " " + shellQuoted(a);
  command += " > " + shellQuoted(outPath) + " 2> " + shellQuoted(errPath);
  const int status = std::system(command.c_str());
  ProgramRun run;
  run.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  run.out = readAndRemove(outPath);
  run.err = readAndRemove(errPath);
  return run;
}

ProgramRun runProgram(const std::string& program, const std::string& argumentLine) {
  std::istringstream words(argumentLine);
  std::vector<std::string> args{std::istream_iterator<std::string>(words), std::istream_iterator<std::string>()};
  return runProgram(program, args);
}

} // namespace cementsph::testing
