// Where the cement pictures look and what they say, worked out from the run's numbers: the z range
// slices.png spans, the side cement_surface.png is seen from, its leak line, the label a point lies in.
// Beside the pictures that use them, so `compare` and `inject` only pass their results in.
#pragma once

#include <array>
#include <cstddef>
#include <initializer_list>
#include <optional>
#include <string>
#include <utility>

class vtkImageData;
class vtkPolyData;

namespace cementsph::rendering {

// The z extent (mm) of the given surfaces' bounds together (null ones skipped). No surface: {fallbackZMm,
// fallbackZMm}, one slice through that height (compare: the injection point, to show where cement should be).
std::pair<double, double> surfacesZRangeMm(std::initializer_list<vtkPolyData*> surfaces, double fallbackZMm);

// cement_surface.png's view direction to see a leak beside the cement in bone: the unit vector from fromMm to
// towardsMm, raised by elevation along +z (a little from above). Empty when the two points are within 1e-6 mm
// (no side to prefer: keep the default view).
std::optional<std::array<double, 3>> viewTowards(const std::array<double, 3>& fromMm,
                                                 const std::array<double, 3>& towardsMm, double elevation = 0.35);

// The legend line of a leak: "leaked 0.027 ml at 1 site" (3 significant digits); empty when leakedMl <= 0.
std::string leakNote(double leakedMl, std::size_t sites);

// The label of a label map at a point (mm, the map's physical space; the nearest voxel), 0 outside the map.
int labelAt(vtkImageData* labels, const std::array<double, 3>& pointMm);

} // namespace cementsph::rendering
