#include "cementsph/imaging/StagedFolder.h"

#include "cementsph/imaging/AtomicFile.h"

#include <unistd.h>

#include <stdexcept>

namespace cementsph::imaging {

namespace fs = std::filesystem;

StagedFolder::StagedFolder(const fs::path& target) : target_(target) {
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  // Remember the outermost folder this run creates, so that a failure removes it again.
  for (fs::path p = parent; !p.empty() && !fs::exists(p); p = p.parent_path()) created_ = p;
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw std::runtime_error(parent.string() + ": cannot create the folder: " + ec.message());
  staging_ = parent / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()));
  fs::remove_all(staging_, ec);
  fs::create_directory(staging_, ec);
  if (ec) throw std::runtime_error(staging_.string() + ": cannot create the folder: " + ec.message());
}

StagedFolder::~StagedFolder() {
  if (published_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
  if (!created_.empty()) fs::remove_all(created_, ec);
}

void StagedFolder::publish(const std::vector<std::string>& staleNumberedPatterns) {
  for (const auto& entry : fs::directory_iterator(staging_))
    if (fs::is_directory(target_ / entry.path().filename()))
      throw std::runtime_error((target_ / entry.path().filename()).string() + " is a folder; nothing was written");
  if (!fs::exists(target_)) {
    fs::rename(staging_, target_);
  } else {
    removeStaleOutputs(target_.string(), staleNumberedPatterns);
    for (const auto& entry : fs::directory_iterator(staging_))
      fs::rename(entry.path(), target_ / entry.path().filename());
    fs::remove(staging_);
  }
  published_ = true;
}

} // namespace cementsph::imaging
