// The layout of `cementsph xray`'s pictures (xray_frames.png, projected_area.png): which frames get a column,
// how a column's time reads, and the two series' colours. Beside the pictures, so the command only passes its
// sequences in.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace cementsph::rendering {

// Outline / curve colours: simulation blue, reference orange (the surface picture's CT is beige, its
// simulation blue).
constexpr std::array<unsigned char, 3> kXraySequenceRgb{0, 110, 255}, kXrayReferenceRgb{255, 120, 0};

// The frames (indices) that get a column: at most maxColumns (2 or more) of frames, evenly spread, first and last
// included. Fewer than 2 frames: each one.
std::vector<std::size_t> xrayFrameColumns(std::size_t frames, int maxColumns);

// A column's time: "t = 12.5 s", one decimal; |t| < 0.05 s reads 0.0 (never "-0.0").
std::string xrayTimeLabel(double timeS);

} // namespace cementsph::rendering
