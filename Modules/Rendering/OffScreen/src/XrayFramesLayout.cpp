#include "cementsph/rendering/XrayFramesLayout.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace cementsph::rendering {

std::vector<std::size_t> xrayFrameColumns(std::size_t frames, int maxColumns) {
  std::vector<std::size_t> columns;
  if (frames < 2) { // the spread below divides by (columns - 1)
    for (std::size_t k = 0; k < frames; ++k) columns.push_back(k);
    return columns;
  }
  const std::size_t m = std::min<std::size_t>(frames, std::size_t(std::max(2, maxColumns)));
  for (std::size_t k = 0; k < m; ++k) {
    const auto index = std::size_t(std::lround(double(k) * double(frames - 1) / double(m - 1)));
    if (columns.empty() || columns.back() != index) columns.push_back(index);
  }
  return columns;
}

std::string xrayTimeLabel(double timeS) {
  std::ostringstream s;
  s << "t = " << std::fixed << std::setprecision(1) << (std::abs(timeS) < 0.05 ? 0.0 : timeS) << " s";
  return s.str();
}

} // namespace cementsph::rendering
