// The projected cement area of X-ray sequences over time (the quantitative side of the paper's Fig. 12,
// Basafa et al. 2013): one curve per sequence (simulation; reference when there is one), drawn with XYPlot.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace cementsph::rendering {

struct ProjectedAreaSeries {
  std::string name;                   // legend entry
  std::vector<double> timeS, areaMm2; // area in the plane of the isocentre
  std::array<unsigned char, 3> rgb{0, 110, 255};
  bool joined = true; // markers joined by lines; false: markers only (a few measured instants)
};

// x "time (s)", y "projected cement area at the isocentre (mm^2)", from 0 to 1.25 x the largest area (room
// for the legend). A series is drawn as markers joined by lines, or as markers only (joined = false, or a
// single point). Errors as writePlotPng() (no series, empty or unequal lengths,
// non-finite values); the file is written atomically.
void writeProjectedAreaPlot(const std::vector<ProjectedAreaSeries>& series, const std::filesystem::path& png,
                            int widthPx = 900, int heightPx = 650);

} // namespace cementsph::rendering
