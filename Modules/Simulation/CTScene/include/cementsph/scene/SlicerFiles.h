// Files 3D Slicer loads by drag and drop, beside an injection's outputs (no .mrb scene needed):
//   injection.mrk.json     the tip (a fiducial) and the cannula's trajectory (a line from the entry, a cannula
//                          length behind the tip, to the tip), Slicer markups JSON (schema v1.0.3), LPS mm
//   leak_sites.mrk.json    one fiducial per leak site (label: class and volume), LPS mm; an empty list when none
//   cement_labels.ctbl     the colour table of cement_labels.nrrd: 1 cement in bone (blue), 2 leaked (red)
//   anatomy_labels.ctbl    the colour table of anatomy_labels.nrrd (anatomy::TissueClass codes): 1 the target
//                          vertebra (green, the slices' outline colour), 2 disc, 3 canal, 4 vessel, 5 other bone
//                          in their leak classes' colours (CementSlices.h); soft tissue 0 and air 6 transparent
// The CT's patient frame is LPS, as Slicer's files declare it (coordinateSystem "LPS"), so no sign flips.
#pragma once

#include "cementsph/scene/InjectionModel.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace cementsph::scene {

nlohmann::json injectionMarkups(const Eigen::Vector3d& tipMm, const Eigen::Vector3d& direction, double cannulaLengthMm);
nlohmann::json leakSiteMarkups(const std::vector<LeakageSite>& sites);
std::string cementLabelColourTable();
std::string anatomyLabelColourTable();

} // namespace cementsph::scene
