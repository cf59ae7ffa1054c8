#include "cementsph/scene/SlicerFiles.h"

#include <cstdio>

namespace cementsph::scene {

using nlohmann::json;

namespace {

const char* const kSchema =
    "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/"
    "markups-schema-v1.0.3.json#";

json controlPoint(const std::string& id, const std::string& label, const std::string& description,
                  const Eigen::Vector3d& mm) {
  return {{"id", id}, {"label", label}, {"description", description}, {"position", {mm.x(), mm.y(), mm.z()}},
          {"locked", true}, {"visibility", true}, {"positionStatus", "defined"}};
}

json markup(const std::string& type, const std::string& name, json points, std::array<double, 3> colour) {
  return {{"type", type}, {"name", name}, {"coordinateSystem", "LPS"}, {"coordinateUnits", "mm"}, {"locked", true},
          {"controlPoints", std::move(points)}, {"display", {{"color", colour}, {"selectedColor", colour}}}};
}

} // namespace

json injectionMarkups(const Eigen::Vector3d& tipMm, const Eigen::Vector3d& direction, double cannulaLengthMm) {
  const Eigen::Vector3d entry = tipMm - cannulaLengthMm * direction.normalized();
  json tip = json::array({controlPoint("1", "tip", "cannula outlet", tipMm)});
  json line = json::array({controlPoint("1", "entry", "cannula, a cannula length behind the tip", entry),
                           controlPoint("2", "tip", "cannula outlet", tipMm)});
  return {{"@schema", kSchema},
          {"markups", json::array({markup("Fiducial", "tip", tip, {1.0, 1.0, 0.0}),
                                   markup("Line", "trajectory", line, {1.0, 1.0, 0.0})})}};
}

json leakSiteMarkups(const std::vector<LeakageSite>& sites) {
  json points = json::array();
  for (std::size_t i = 0; i < sites.size(); ++i) {
    char label[96];
    std::snprintf(label, sizeof label, "leak %zu: %s %.3g ml", i + 1, sites[i].siteClass.c_str(), sites[i].volumeMl);
    const auto& p = sites[i].positionMm;
    char when[64];
    std::snprintf(when, sizeof when, "first cement at %.3g s", sites[i].firstTimeS);
    points.push_back(controlPoint(std::to_string(i + 1), label, when, Eigen::Vector3d(p[0], p[1], p[2])));
  }
  return {{"@schema", kSchema}, {"markups", json::array({markup("Fiducial", "leak sites", points, {1.0, 0.0, 0.0})})}};
}

std::string cementLabelColourTable() {
  return "# Colour table of cement_labels.nrrd (3D Slicer): index name R G B A\n"
         "0 background 0 0 0 0\n"
         "1 cement_in_bone 51 128 255 255\n"
         "2 leaked_cement 230 25 25 255\n";
}

std::string anatomyLabelColourTable() {
  return "# Colour table of anatomy_labels.nrrd (3D Slicer): index name R G B A (anatomy::TissueClass codes)\n"
         "0 other_soft_tissue 0 0 0 0\n"
         "1 target_vertebra 0 200 80 255\n"
         "2 disc 220 0 220 255\n"
         "3 canal 255 140 0 255\n"
         "4 vessel 140 70 255 255\n"
         "5 other_bone 150 90 30 255\n"
         "6 air 0 0 0 0\n";
}

} // namespace cementsph::scene
