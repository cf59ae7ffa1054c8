#include "OutputFiles.h"

#include "cementsph/imaging/AtomicFile.h"

#include "cementsph/rendering/XYPlot.h"
#include "cementsph/sph/DarcyBenchmark.h"

#include <algorithm>
#include <chrono>
#include <iostream>
#include <map>
#include <sstream>

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

void writeDarcyPlot(const std::vector<sph::DarcyResult>& results, const std::filesystem::path& png) {
  using rendering::PlotSeries;
  rendering::PlotSpec spec;
  spec.title = "Dimensionless permeability k/d^2 against porosity (Eq. 12)";
  spec.xLabel = "porosity";
  spec.yLabel = "k / d^2 (d: particle spacing)";
  spec.logY = true;
  // One series per spacing and viscosity: Darcy's law says they should fall on one curve.
  std::map<std::pair<double, double>, PlotSeries> bySet;
  double lo = 1.0, hi = 0.0;
  for (const sph::DarcyResult& r : results) {
    if (!(r.dimensionlessPermeability > 0)) continue; // not drawable on a log axis
    PlotSeries& s = bySet[{r.input.spacing, r.input.viscosity}];
    if (s.name.empty()) {
      std::ostringstream n;
      n << "SPH, d " << r.input.spacing * 1e3 << " mm, " << r.input.viscosity << " Pa.s";
      s.name = n.str();
      s.style = PlotSeries::Style::LineAndPoints;
    }
    s.x.push_back(r.porosity);
    s.y.push_back(r.dimensionlessPermeability);
    lo = std::min(lo, r.porosity);
    hi = std::max(hi, r.porosity);
  }
  if (bySet.empty()) throw std::runtime_error(png.string() + ": no positive permeability to plot");
  const std::array<std::array<unsigned char, 3>, 6> palette{
      {{31, 119, 180}, {255, 127, 14}, {44, 160, 44}, {148, 103, 189}, {140, 86, 75}, {227, 119, 194}}};
  std::size_t k = 0;
  for (auto& [key, series] : bySet) {
    series.rgb = palette[k++ % palette.size()];
    if (series.x.size() < 2) series.style = PlotSeries::Style::Points; // a line needs two points
    spec.series.push_back(series);
  }
  // Kozeny-Carman with the spacing as grain diameter, over the same porosity range (phi < 1).
  PlotSeries kc;
  kc.name = "Kozeny-Carman, phi^3 / (180 (1 - phi)^2)";
  kc.style = PlotSeries::Style::Line;
  kc.rgb = {0, 0, 0};
  const double top = std::min(hi, 0.95);
  for (int i = 0; i <= 50 && lo < top; ++i) {
    const double phi = lo + (top - lo) * i / 50.0;
    kc.x.push_back(phi);
    kc.y.push_back(sph::kozenyCarmanDimensionless(phi));
  }
  if (kc.x.size() > 1) spec.series.push_back(kc);
  rendering::writePlotPng(spec, png);
}

} // namespace cementsph::app
