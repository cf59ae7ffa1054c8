// Image comparison for rendering regression tests, in the manner of VTK's baseline tests.
#pragma once

#include <filesystem>

namespace cementsph::rendering {

// Mean absolute difference of the colour channels of two PNG files, each channel scaled to [0, 1]:
// 0 for identical images, 1 for black against white everywhere. Grey images count as R = G = B and
// alpha is ignored, so an RGB and an RGBA rendering of the same picture compare as equal.
// Throws std::runtime_error if a file cannot be read as PNG or the two sizes differ.
double imageDifference(const std::filesystem::path& a, const std::filesystem::path& b);

} // namespace cementsph::rendering
