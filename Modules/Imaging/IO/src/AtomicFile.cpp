#include "cementsph/imaging/AtomicFile.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <unistd.h>

namespace cementsph::imaging {

namespace fs = std::filesystem;

std::string fullExtension(const std::string& path) {
  std::string name = fs::path(path).filename().string();
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  // Compound extensions first: ".nii.gz" must not be taken for ".gz".
  for (const char* compound : {".nii.gz", ".vtk.gz"}) {
    const std::string ext(compound);
    if (name.size() > ext.size() && name.compare(name.size() - ext.size(), ext.size(), ext) == 0)
      return ext;
  }
  const auto dot = name.rfind('.');
  if (dot == std::string::npos || dot == 0) return {};
  return name.substr(dot);
}

std::string temporarySiblingPath(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  const std::string ext = fullExtension(path);
  const std::string stem = path.substr(0, path.size() - ext.size());
  return stem + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ext;
}

void writeAtomically(const std::string& path,
                     const std::function<void(const std::string&)>& write) {
  const std::string tmp = temporarySiblingPath(path);
  try {
    write(tmp);
    std::error_code ec;
    const auto size = fs::file_size(tmp, ec);
    if (ec || size == 0) throw std::runtime_error("the writer left no data (disk full?)");
    fs::rename(tmp, path, ec);
    if (ec) throw std::runtime_error("cannot rename into place: " + ec.message());
  } catch (const std::exception& e) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    const std::string what = e.what();
    // Do not repeat the path if the writer already named it.
    throw OutputError(what.find(path) != std::string::npos ? what : path + ": " + what);
  }
}

void writeTextAtomically(const std::string& path, const std::string& text) {
  writeAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw std::runtime_error("cannot open for writing");
    out << text;
    out.close();
    if (!out) throw std::runtime_error("write failed (disk full or over the file size limit?)");
  });
}

namespace {

bool matchesNumbered(const std::string& name, const std::string& pattern) {
  if (name.size() != pattern.size()) return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    if (pattern[i] == '#' ? !std::isdigit(static_cast<unsigned char>(name[i])) : name[i] != pattern[i]) return false;
  }
  return true;
}

// "a.tmp-123-4.nrrd" (writeAtomically) or "a.csv.tmp-123" (older writers): ".tmp-" then a digit.
bool isTemporary(const std::string& name) {
  const auto at = name.find(".tmp-");
  return at != std::string::npos && at + 5 < name.size() && std::isdigit(static_cast<unsigned char>(name[at + 5]));
}

} // namespace

std::size_t removeStaleOutputs(const std::string& directory, const std::vector<std::string>& numberedPatterns) {
  std::error_code ec;
  if (!fs::is_directory(directory, ec)) return 0;
  std::vector<fs::path> stale;
  for (fs::directory_iterator it(directory, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    const std::string name = it->path().filename().string();
    bool remove = isTemporary(name);
    for (const std::string& pattern : numberedPatterns) remove = remove || matchesNumbered(name, pattern);
    if (remove) stale.push_back(it->path());
  }
  std::size_t removed = 0;
  for (const fs::path& p : stale)
    if (fs::remove(p, ec)) ++removed;
  return removed;
}

} // namespace cementsph::imaging
