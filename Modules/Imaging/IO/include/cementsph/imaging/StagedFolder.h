// A transactional output folder: a run's files are written into a temporary sibling folder and moved into
// place only when everything has been written, so bad input or a failed write leaves no partial output
// (the folder-level counterpart of AtomicFile.h's writeAtomically).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace cementsph::imaging {

class StagedFolder {
public:
  // Creates the target's parent (remembering the outermost folder it had to create) and an empty staging
  // folder ".NAME.tmp-PID" beside the target. Throws std::runtime_error naming a folder it cannot create.
  explicit StagedFolder(const std::filesystem::path& target);
  // Without publish(): the staging folder and the parent folders this object created are removed.
  ~StagedFolder();
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;

  // Where to write the files.
  const std::filesystem::path& path() const { return staging_; }

  // Moves the files into the target (created when absent; files of the same name replaced). A folder in the
  // way of a file is found before anything moves (std::runtime_error, nothing moved). In an existing target,
  // an earlier run's files matching staleNumberedPatterns (removeStaleOutputs' "name_####.ext") go first, so
  // that its numbered frames do not mix with this run's.
  void publish(const std::vector<std::string>& staleNumberedPatterns = {});

private:
  std::filesystem::path target_, staging_, created_;
  bool published_ = false;
};

} // namespace cementsph::imaging
