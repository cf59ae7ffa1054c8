// The DRR options that `cementsph drr` and `cementsph xray` share: one definition of the geometry options
// (names, units, help) and their checks, so the two commands cannot drift apart. The files a DRR becomes
// (drr.nrrd, the windowed PNG, a sequence's frames) are the DRR module's: cementsph/drr/DRRFiles.h.
#pragma once

#include "cementsph/drr/DRRGeometry.h"

#include <CLI/CLI.hpp>

#include <array>
#include <string>
#include <vector>

namespace cementsph::app {

struct DrrGeometryArgs {
  drr::DRRGeometry geometry;           // sad, sid, gantry angle, parallel: set by the options directly
  std::vector<int> pixels{512, 512};   // rows, cols
  std::vector<double> sizeMm{400.0, 400.0}; // height, width
  std::vector<double> isocenterMm;     // empty: the volume's centre
  int threads = 0;
  CLI::Option* sizeOption = nullptr;   // to tell whether --detector-size-mm was given
};

// Adds --sad-mm, --sid-mm, --detector-pixels, --detector-size-mm, --isocenter-mm, --gantry-angle-deg,
// --parallel and --threads. sizeHelp: the help of --detector-size-mm (its default differs by command).
void addDrrGeometryOptions(CLI::App& sub, DrrGeometryArgs& args, const std::string& sizeHelp);

// The geometry the options give before any volume is read (isocentre still at the origin). Throws
// std::runtime_error with DRRGeometry::validate()'s sentence, or for negative --threads.
drr::DRRGeometry checkedGeometry(const DrrGeometryArgs& args);

// The geometry for a volume whose voxel centres span boundsMm ({xmin, xmax, ymin, ymax, zmin, zmax}): the
// isocentre is the box's centre unless --isocenter-mm was given; with fitDetector the detector size is
// fitted to the box's projection (DRRGeometry::fitDetectorTo, 10 % margin, square pixels). Throws
// std::runtime_error when the result is unusable.
drr::DRRGeometry geometryForVolume(const DrrGeometryArgs& args, const std::array<double, 6>& boundsMm, bool fitDetector);

} // namespace cementsph::app
