#include "OutputFiles.h"

#include "cementsph/imaging/AtomicFile.h"


#include <algorithm>
#include <chrono>
#include <iostream>

#include <stdexcept>

#include <unistd.h>

namespace cementsph::app {

bool PictureSteps::draw(const std::string& name, const std::filesystem::path& png,
                        const std::function<void(const std::filesystem::path&)>& draw) {
  try {
    draw(png);
    written_.push_back(name);
    return true;
  } catch (const std::exception& e) {
    std::cerr << "cementsph " << command_ << ": picture " << name << " not written (" << kept_
              << " are): " << e.what() << "\n";
    failed_ = true;
    return false;
  }
}

bool PictureSteps::drawAndAnnounce(const std::string& name, const std::filesystem::path& png,
                                   const std::function<void(const std::filesystem::path&)>& draw) {
  const auto start = std::chrono::steady_clock::now();
  if (!this->draw(name, png, draw)) return false;
  std::cout << "wrote " << png.string() << " ("
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() << " s)\n";
  return true;
}

void checkOutputFolder(const std::filesystem::path& out) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw std::runtime_error(out.string() + ": exists and is not a folder");
  fs::path p = fs::absolute(out, ec);
  while (!p.empty() && !fs::exists(p, ec) && p != p.parent_path()) p = p.parent_path();
  if (access(p.c_str(), W_OK) != 0) throw std::runtime_error(out.string() + ": cannot write in " + p.string());
}

void writeFileAtomically(const std::filesystem::path& path, const std::string& contents) {
  imaging::writeTextAtomically(path.string(), contents);
}

} // namespace cementsph::app
