#include "cementsph/planning/PlanTrajectory.h"

#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/planning/InjectionPlanner.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

namespace cementsph::planning {

anatomy::Anatomy anatomyAround(const imaging::ImageType* ct, const scene::SceneConfig& scene,
                               const Eigen::Vector3d& seedMm, const std::vector<Eigen::Vector3d>& alsoHold,
                               double cubeMm) {
  const auto region = ct->GetLargestPossibleRegion();
  const auto spacing = ct->GetSpacing();
  // The box in index space: a ball of radius r about a point spans +- r / spacing along every index axis
  // whatever the direction matrix (its axes are orthonormal).
  double lo[3], hi[3];
  std::fill(lo, lo + 3, std::numeric_limits<double>::infinity());
  std::fill(hi, hi + 3, -std::numeric_limits<double>::infinity());
  auto hold = [&](const Eigen::Vector3d& p, double marginMm) {
    imaging::ImageType::PointType q;
    for (unsigned a = 0; a < 3; ++a) q[a] = p[int(a)];
    itk::ContinuousIndex<double, 3> ci;
    ct->TransformPhysicalPointToContinuousIndex(q, ci);
    for (unsigned a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], ci[a] - marginMm / spacing[a]);
      hi[a] = std::max(hi[a], ci[a] + marginMm / spacing[a]);
    }
  };
  hold(seedMm, 0.5 * cubeMm);
  for (const auto& p : alsoHold) hold(p, 5.0);
  imaging::ImageType::IndexType start;
  anatomy::Grid grid;
  for (unsigned a = 0; a < 3; ++a) {
    const double first = double(region.GetIndex()[a]), last = first + double(region.GetSize()[a]) - 1;
    const double from = std::clamp(std::floor(lo[a]), first, last), to = std::clamp(std::ceil(hi[a]), first, last);
    start[a] = itk::IndexValueType(from);
    grid.size[a] = int(to - from) + 1;
    grid.spacingMm[a] = spacing[a];
    for (unsigned r = 0; r < 3; ++r) grid.direction[3 * r + a] = ct->GetDirection()(r, a);
  }
  imaging::ImageType::PointType origin;
  ct->TransformIndexToPhysicalPoint(start, origin);
  for (unsigned a = 0; a < 3; ++a) grid.originMm[a] = origin[a];

  imaging::ImageType::Pointer labelMap;
  if (!scene.labelsPath.empty()) {
    labelMap = imaging::readVolume(scene.labelsPath);
    if (!imaging::geometryOf(labelMap).sameGrid(imaging::geometryOf(ct)))
      throw std::invalid_argument("labels " + scene.labelsPath +
                                  ": the label map is not on the CT's grid (size, origin, spacing, direction); export "
                                  "it on the CT's grid (TotalSegmentator and 3D Slicer do)");
  }
  std::vector<float> hu;
  std::vector<std::int32_t> labels;
  hu.reserve(grid.count());
  for (int k = 0; k < grid.size[2]; ++k)
    for (int j = 0; j < grid.size[1]; ++j)
      for (int i = 0; i < grid.size[0]; ++i) {
        imaging::ImageType::IndexType idx{{start[0] + i, start[1] + j, start[2] + k}};
        hu.push_back(ct->GetPixel(idx));
        if (labelMap) labels.push_back(std::int32_t(std::lround(labelMap->GetPixel(idx))));
      }
  anatomy::AnatomyOptions options;
  options.softTissueMaxHu = scene.bone.softTissueMaxHu;
  options.corticalHu = scene.bone.corticalHu;
  const std::array<double, 3> seed{seedMm.x(), seedMm.y(), seedMm.z()};
  if (!labelMap) return anatomy::classifyAnatomyFromCT(hu.data(), grid, seed, options);
  anatomy::LabelTable table = anatomy::LabelTable::totalSegmentator();
  if (!scene.labelTable.is_null()) {
    try {
      table = anatomy::LabelTable::fromJson(scene.labelTable);
    } catch (const std::exception& e) {
      throw std::invalid_argument(std::string("scene: label_table: ") + e.what());
    }
  }
  return anatomy::classifyAnatomyFromLabels(hu.data(), labels.data(), grid, seed, table, options);
}

Eigen::Vector3d shaftEndMm(const PlanRequest& r) {
  const Eigen::Vector3d axis = r.direction.normalized();
  const double foot = (r.targetCentreMm - r.entryMm).dot(axis);
  return r.entryMm + (foot > 0 ? std::min(foot, r.maxDepthMm) : r.maxDepthMm) * axis;
}

anatomy::TrajectoryCheck checkPlanTrajectory(const imaging::ImageType* ct, const PlanRequest& r) {
  const Eigen::Vector3d end = shaftEndMm(r);
  const anatomy::Anatomy a = anatomyAround(ct, r.scene, r.targetCentreMm, {r.entryMm, end});
  return anatomy::checkTrajectory(a, {r.entryMm.x(), r.entryMm.y(), r.entryMm.z()}, {end.x(), end.y(), end.z()});
}

} // namespace cementsph::planning
