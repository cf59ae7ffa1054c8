#include "cementsph/rendering/CementPictureLayout.h"

#include <vtkImageData.h>
#include <vtkPolyData.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace cementsph::rendering {

std::pair<double, double> surfacesZRangeMm(std::initializer_list<vtkPolyData*> surfaces, double fallbackZMm) {
  double lo = 1e300, hi = -1e300;
  for (vtkPolyData* surface : surfaces) {
    if (surface == nullptr) continue;
    double b[6];
    surface->GetBounds(b);
    lo = std::min(lo, b[4]);
    hi = std::max(hi, b[5]);
  }
  // No surface (an empty one's bounds are inverted too): one slice at the fallback height.
  return lo <= hi ? std::make_pair(lo, hi) : std::make_pair(fallbackZMm, fallbackZMm);
}

std::optional<std::array<double, 3>> viewTowards(const std::array<double, 3>& fromMm,
                                                 const std::array<double, 3>& towardsMm, double elevation) {
  double d[3], norm = 0;
  for (int axis = 0; axis < 3; ++axis) {
    d[axis] = towardsMm[std::size_t(axis)] - fromMm[std::size_t(axis)];
    norm += d[axis] * d[axis];
  }
  norm = std::sqrt(norm);
  if (!(norm > 1e-6)) return std::nullopt;
  std::array<double, 3> view{};
  for (int axis = 0; axis < 3; ++axis) view[std::size_t(axis)] = d[axis] / norm + (axis == 2 ? elevation : 0.0);
  return view;
}

std::string leakNote(double leakedMl, std::size_t sites) {
  if (!(leakedMl > 0)) return {};
  std::ostringstream note;
  note << std::setprecision(3) << "leaked " << leakedMl << " ml at " << sites << (sites == 1 ? " site" : " sites");
  return note.str();
}

int labelAt(vtkImageData* labels, const std::array<double, 3>& pointMm) {
  double point[3] = {pointMm[0], pointMm[1], pointMm[2]}, index[3];
  labels->TransformPhysicalPointToContinuousIndex(point, index);
  int ijk[3], dims[3];
  labels->GetDimensions(dims);
  for (int a = 0; a < 3; ++a) {
    ijk[a] = int(std::lround(index[a]));
    if (ijk[a] < 0 || ijk[a] >= dims[a]) return 0;
  }
  return int(std::lround(labels->GetScalarComponentAsDouble(ijk[0], ijk[1], ijk[2], 0)));
}

} // namespace cementsph::rendering
