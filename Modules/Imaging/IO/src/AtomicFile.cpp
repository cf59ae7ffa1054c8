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
    fs::rename(tmp, path, ec);
    if (ec) throw std::runtime_error("cannot rename into place: " + ec.message());
  } catch (const std::exception& e) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    const std::string what = e.what();
    // Do not repeat the path if the writer already named it.
    if (what.find(path) != std::string::npos) throw;
    throw std::runtime_error(path + ": " + what);
  }
}

void writeTextAtomically(const std::string& path, const std::string& text) {
  writeAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw std::runtime_error("cannot open for writing");
    out << text;
    out.close();
    if (!out) throw std::runtime_error("write failed (disk full?)");
  });
}

} // namespace cementsph::imaging
