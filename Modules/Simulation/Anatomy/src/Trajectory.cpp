#include "cementsph/anatomy/Trajectory.h"

#include "cementsph/anatomy/LeakSites.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace cementsph::anatomy {

namespace {

std::string point(const std::array<double, 3>& p) {
  std::ostringstream s;
  s << std::setprecision(4) << "(" << p[0] << ", " << p[1] << ", " << p[2] << ") mm";
  return s.str();
}

bool softOrAir(TissueClass c) { return c == TissueClass::OtherSoftTissue || c == TissueClass::Air; }

} // namespace

nlohmann::json TrajectoryCheck::toJson() const {
  nlohmann::json c = nlohmann::json::array();
  for (const auto& x : crossings)
    c.push_back({{"kind", x.kind},
                 {"tissue", className(x.tissue)},
                 {"from_depth_mm", x.fromDepthMm},
                 {"to_depth_mm", x.toDepthMm},
                 {"first_mm", x.firstMm}});
  return {{"entry_mm", entryMm},
          {"end_mm", endMm},
          {"length_mm", lengthMm},
          {"step_mm", stepMm},
          {"reaches_vertebra_depth_mm", reachesVertebraMm >= 0 ? nlohmann::json(reachesVertebraMm) : nlohmann::json(nullptr)},
          {"crossings", c},
          {"verdict", verdict},
          {"anatomy_rule", rule},
          {"message", message},
          {"rule",
           "the shaft sampled every quarter voxel, nearest voxel's class; after it reaches the target vertebra any "
           "other class is a crossing (soft tissue or air only over at least min_breach_mm); the canal is refused, "
           "any other crossing is a warning"}};
}

TrajectoryCheck checkTrajectory(const Anatomy& anatomy, const std::array<double, 3>& entryMm,
                                const std::array<double, 3>& endMm, const TrajectoryOptions& options) {
  TrajectoryCheck check;
  check.entryMm = entryMm;
  check.endMm = endMm;
  check.rule = anatomy.rule;
  double axis[3], length = 0;
  for (int a = 0; a < 3; ++a) {
    axis[a] = endMm[std::size_t(a)] - entryMm[std::size_t(a)];
    length += axis[a] * axis[a];
  }
  length = std::sqrt(length);
  if (!std::isfinite(length) || !(length > 0))
    throw std::invalid_argument("trajectory check: the shaft from " + point(entryMm) + " to " + point(endMm) +
                                " has no length");
  for (double& c : axis) c /= length;
  check.lengthMm = length;
  const auto& s = anatomy.grid.spacingMm;
  check.stepMm = 0.25 * std::min({s[0], s[1], s[2]});
  if (!anatomy.targetFound) {
    check.verdict = "unchecked";
    check.message = "no target vertebra was found around the target (" + anatomy.description +
                    "): the trajectory was not checked";
    return check;
  }
  // Classes along the shaft, then runs of one class.
  const int samples = int(std::floor(length / check.stepMm)) + 1;
  auto at = [&](int i) {
    const double d = std::min(length, i * check.stepMm);
    return std::array<double, 3>{entryMm[0] + d * axis[0], entryMm[1] + d * axis[1], entryMm[2] + d * axis[2]};
  };
  auto depth = [&](int i) { return std::min(length, i * check.stepMm); };
  bool inVertebra = false;
  for (int i = 0; i < samples;) {
    const TissueClass c = anatomy.atPoint(at(i));
    int j = i;
    while (j + 1 < samples && anatomy.atPoint(at(j + 1)) == c) ++j;
    if (c == TissueClass::TargetVertebra) {
      if (!inVertebra) check.reachesVertebraMm = depth(i);
      inVertebra = true;
    } else {
      // On the approach soft tissue and air are expected; inside, they must be more than a seam (a run's extent
      // is from its first sample to its last: one voxel along the shaft spans a voxel less one step), and a run
      // that ends the shaft (the deepest tip out of the bone) counts whatever its length.
      const bool seam = softOrAir(c) && depth(j) - depth(i) < options.minBreachMm && j + 1 < samples;
      // One crossing, not two, where a voxel of another class (the canal's partial-volume rim) splits it.
      if (!(softOrAir(c) && !inVertebra) && !seam) {
        if (!check.crossings.empty() && check.crossings.back().tissue == c &&
            depth(i) - check.crossings.back().toDepthMm - 2 * check.stepMm < options.minBreachMm)
          check.crossings.back().toDepthMm = depth(j);
        else
          check.crossings.push_back({c, leakKind(c), depth(i), depth(j), at(i)});
      }
    }
    i = j + 1;
  }
  const bool canal = std::any_of(check.crossings.begin(), check.crossings.end(),
                                 [](const TrajectoryCrossing& x) { return x.tissue == TissueClass::Canal; });
  check.verdict = canal ? "refused" : check.crossings.empty() ? "clear" : "warning";
  std::ostringstream m;
  m << std::setprecision(3);
  if (check.crossings.empty()) {
    m << "the shaft from " << point(entryMm) << " to " << point(endMm);
    if (inVertebra) m << " stays in the target vertebra from " << check.reachesVertebraMm << " mm on";
    else m << " does not reach the target vertebra";
  } else {
    m << "the shaft from " << point(entryMm) << " crosses ";
    for (std::size_t k = 0; k < check.crossings.size(); ++k) {
      const auto& x = check.crossings[k];
      m << (k == 0 ? "" : "; then ")
        << (softOrAir(x.tissue) ? "out of the target vertebra into " + std::string(tissueWords(x.tissue))
                                : std::string(tissueWords(x.tissue)))
        << " " << x.fromDepthMm << " to " << x.toDepthMm << " mm from the entry (first at " << point(x.firstMm) << ")";
    }
  }
  check.message = m.str();
  return check;
}

} // namespace cementsph::anatomy
