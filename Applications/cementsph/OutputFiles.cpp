#include "OutputFiles.h"

#include "cementsph/sph/DarcyBenchmark.h"

#include <fstream>
#include <iostream>
#include <random>
#include <stdexcept>
#include <system_error>

namespace cementsph::app {

void writeFileAtomically(const std::filesystem::path& path, const std::string& contents) {
  const std::filesystem::path tmp = path.string() + ".tmp-" + std::to_string(std::random_device{}());
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw std::runtime_error(path.string() + ": cannot open for writing");
    out << contents;
    out.flush();
    if (!out) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw std::runtime_error(path.string() + ": write failed");
    }
  }
  std::filesystem::rename(tmp, path);
}

void writeDarcyPlot(const std::vector<sph::DarcyResult>&, const std::filesystem::path& png) {
  std::cerr << "note: " << png.string() << " not written: plotting arrives with the rendering module\n";
}

} // namespace cementsph::app
