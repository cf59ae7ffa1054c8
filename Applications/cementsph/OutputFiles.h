// Output helpers shared by subcommands: every file is written to a temporary name in its folder
// and renamed into place, so a failure never leaves a partial file behind.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace cementsph::app {

// The picture steps of a command, after its numbers are written: a picture that fails is one line on stderr
// ("cementsph COMMAND: picture NAME not written (KEPT are): why") and makes the exit status 3, because the
// user asked for it (pictures are on by default) and a script should notice it is missing, while everything
// already written stays valid.
class PictureSteps {
public:
  // kept: what the failure line says is written all the same ("the numbers", "metrics", "the tables").
  explicit PictureSteps(std::string command, std::string kept = "the numbers")
      : command_(std::move(command)), kept_(std::move(kept)) {}
  // Runs draw(png). name is the picture as the failure line names it. Returns whether it was written.
  bool draw(const std::string& name, const std::filesystem::path& png,
            const std::function<void(const std::filesystem::path&)>& draw);
  // The same, and on success one line "wrote PNG (T s)" on stdout.
  bool drawAndAnnounce(const std::string& name, const std::filesystem::path& png,
                       const std::function<void(const std::filesystem::path&)>& draw);
  int status() const { return failed_ ? 3 : 0; }
  // The names of the pictures written, in order.
  const std::vector<std::string>& written() const { return written_; }

private:
  std::string command_, kept_;
  std::vector<std::string> written_;
  bool failed_ = false;
};

// Refuses, before anything runs, an output path that is a file or lies under a folder we cannot write.
void checkOutputFolder(const std::filesystem::path& out);

void writeFileAtomically(const std::filesystem::path& path, const std::string& contents);

} // namespace cementsph::app
