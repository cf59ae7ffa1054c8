// Image comparison for rendering regression tests, in the manner of VTK's baseline tests
// (vtkImageDifference): small anti-aliasing and one-pixel placement changes between GL drivers or font
// versions should not count, a changed curve should.
#pragma once

#include <filesystem>

namespace cementsph::rendering {

// Fraction of pixels, in [0, 1], that differ visibly between two PNG files of the same size. A pixel
// differs visibly if in some colour channel it is more than kVisibleChannelDifference away from every
// pixel of the 3 x 3 neighbourhood at the same place in the other image (checked both ways), so an
// image shifted by one pixel scores 0. Plots are mostly background, so a real change is a small fraction:
// moving a few markers of a 900 x 650 plot gives ~1e-3.
// Grey images count as R = G = B; alpha is ignored. Throws std::runtime_error if a file cannot be read
// as PNG or the sizes differ.
double imageDifference(const std::filesystem::path& a, const std::filesystem::path& b);

// Channel difference (channels scaled to [0, 1]) above which imageDifference() sees a pixel as changed.
inline constexpr double kVisibleChannelDifference = 0.1;

// Mean absolute difference of the colour channels, each scaled to [0, 1]: 0 for identical images, 1 for
// black against white everywhere. Strict (no shift allowance); same conventions and errors as above.
double meanAbsoluteDifference(const std::filesystem::path& a, const std::filesystem::path& b);

} // namespace cementsph::rendering
