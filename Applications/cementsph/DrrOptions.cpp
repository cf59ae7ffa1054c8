#include "DrrOptions.h"

#include <stdexcept>

namespace cementsph::app {

void addDrrGeometryOptions(CLI::App& sub, DrrGeometryArgs& a, const std::string& sizeHelp) {
  auto& g = a.geometry;
  sub.add_option("--sad-mm", g.sadMm, "Source-axis distance, mm")->capture_default_str();
  sub.add_option("--sid-mm", g.sidMm, "Source-image (detector) distance, mm")->capture_default_str();
  sub.add_option("--detector-pixels", a.pixels, "Detector resolution in pixels: rows,cols")
      ->delimiter(',')
      ->expected(2)
      ->capture_default_str();
  a.sizeOption = sub.add_option("--detector-size-mm", a.sizeMm, sizeHelp)->delimiter(',')->expected(2);
  sub.add_option("--isocenter-mm", a.isocenterMm,
                 "Isocentre in the volume's physical coordinates, mm: x,y,z (default: the volume's centre)")
      ->delimiter(',')
      ->expected(3);
  sub.add_option("--gantry-angle-deg", g.gantryAngleDeg,
                 "Gantry angle about z, degrees (0: source on +x, 90: source on -y; plastimatch's sense)")
      ->capture_default_str();
  sub.add_flag("--parallel", g.parallel, "Parallel beam along the beam axis (sad/sid unused)");
  sub.add_option("--threads", a.threads, "OpenMP threads (0: the cores the load average leaves free)")->capture_default_str();
}

namespace {

// The geometry's own words name the quantity; the user typed an option: name it first.
[[noreturn]] void refuseGeometry(const std::string& problem) {
  const char* option = problem.find("source-image") != std::string::npos   ? "--sid-mm"
                       : problem.find("source-axis") != std::string::npos  ? "--sad-mm"
                       : problem.find("pixels") != std::string::npos       ? "--detector-pixels"
                       : problem.find("detector size") != std::string::npos ? "--detector-size-mm"
                                                                            : "";
  throw std::runtime_error(*option ? std::string(option) + ": " + problem : problem);
}

} // namespace

drr::DRRGeometry checkedGeometry(const DrrGeometryArgs& a) {
  if (a.threads < 0) throw std::runtime_error("--threads must be 0 or more");
  // A flat-panel detector has about 3000 pixels a side: 8192 leaves room, and 46341 x 46341 (2^31 pixels, 8 GB
  // of doubles) ran for minutes before running out of memory.
  constexpr int kMaxDetectorPixels = 8192;
  if (a.pixels[0] > kMaxDetectorPixels || a.pixels[1] > kMaxDetectorPixels)
    throw std::runtime_error("--detector-pixels " + std::to_string(a.pixels[0]) + "," + std::to_string(a.pixels[1]) +
                             ": at most " + std::to_string(kMaxDetectorPixels) +
                             " a side (a flat-panel detector has about 3000)");
  drr::DRRGeometry g = a.geometry;
  g.rows = a.pixels[0];
  g.cols = a.pixels[1];
  g.heightMm = a.sizeMm[0];
  g.widthMm = a.sizeMm[1];
  if (const std::string problem = g.validate(); !problem.empty()) refuseGeometry(problem);
  return g;
}

drr::DRRGeometry geometryForVolume(const DrrGeometryArgs& a, const std::array<double, 6>& b, bool fitDetector) {
  drr::DRRGeometry g = checkedGeometry(a);
  if (a.isocenterMm.empty())
    g.isocenterMm = {0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5])};
  else
    g.isocenterMm = {a.isocenterMm[0], a.isocenterMm[1], a.isocenterMm[2]};
  // A cone beam's source must lie outside the volume, in front of all of it: one inside (--sad-mm 1e-300) drew
  // a DRR of rays that start within the CT, without a word.
  if (!g.parallel) {
    const auto beam = g.beamDirection();
    for (int c = 0; c < 8; ++c) {
      const double rel[3] = {b[(c & 1) ? 1 : 0] - g.isocenterMm[0], b[(c & 2) ? 3 : 2] - g.isocenterMm[1],
                             b[(c & 4) ? 5 : 4] - g.isocenterMm[2]};
      if (!(g.sadMm + rel[0] * beam[0] + rel[1] * beam[1] + rel[2] * beam[2] > 0))
        throw std::runtime_error("--sad-mm " + std::to_string(g.sadMm) + ": the source lies inside or behind the volume "
                                 "(seen from the isocentre); give a --sad-mm larger than the volume's reach");
    }
  }
  try {
    if (fitDetector) g.fitDetectorTo(b, 1.1);
  } catch (const std::invalid_argument& e) {
    // The geometry names no option (and its own name is no help): say which ones place the source.
    std::string why = e.what();
    if (why.rfind("fitDetectorTo: ", 0) == 0) why.erase(0, 15);
    throw std::runtime_error("--sad-mm " + std::to_string(g.sadMm) + " with --isocenter-mm and --gantry-angle-deg: cannot fit "
                             "the detector to the volume (" + why + "); give a larger --sad-mm or an isocentre "
                             "inside the volume");
  }
  if (const std::string problem = g.validate(); !problem.empty()) throw std::runtime_error(problem);
  return g;
}

} // namespace cementsph::app
