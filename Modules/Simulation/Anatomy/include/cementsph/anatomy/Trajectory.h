// Does a cannula's straight shaft stay in the pedicle and the vertebra (issue 20, item 4)? The shaft from the
// entry point to its end (the tip, or the deepest tip a plan may place) is sampled every quarter of the
// smallest voxel spacing; each sample takes the class of its nearest voxel on the anatomy's own grid (world ->
// index through the grid's direction matrix: Grid::continuousIndex), so an oblique CT is read as it was scanned.
//
// The rule (what a spine surgeon checks on the planning CT):
//  - The approach: samples before the shaft first reaches the target vertebra are soft tissue or air, as
//    expected. The canal, a vessel, a disc or another bone met there are crossings all the same.
//  - After the shaft has reached the target vertebra, every run of samples of another class is a crossing:
//    the spinal canal, a vessel, a disc (through an end plate), another bone, or soft tissue / air (the shaft
//    leaves the vertebra through its cortex: a pedicle or wall breach). A run of soft tissue or air shorter
//    than minBreachMm is a partial-volume seam between two bony voxels (the pedicle's base on a 1 mm grid), not
//    a breach; the canal, a vessel and a disc count from their first sample. Two runs of one class less than
//    minBreachMm apart are one crossing (a voxel of the canal's rim classed otherwise does not split it).
//  - Verdict: "refused" when the shaft crosses the spinal canal (the cord or the cauda equina: never a path),
//    "warning" for any other crossing, "clear" for none; "unchecked" when no target vertebra was found (the
//    runs then refuse their tips, naming the tissue). A shaft that never reaches the vertebra is not a crossing:
//    its tips are outside bone and each run says so.
// Each crossing names its class, the depths (mm from the entry) of its first and last samples and the first
// sample's position (LPS mm): within one voxel of the true boundary where the anatomy's classes are right.
#pragma once

#include "cementsph/anatomy/VertebraAnatomy.h"

#include <nlohmann/json.hpp>

#include <array>
#include <string>
#include <vector>

namespace cementsph::anatomy {

struct TrajectoryOptions {
  double minBreachMm = 1.0; // shorter runs of soft tissue or air inside the bone are partial-volume seams
};

struct TrajectoryCrossing {
  TissueClass tissue = TissueClass::OtherSoftTissue;
  std::string kind;     // leakKind()'s words: "canal", "venous", "disc", "other_bone", "cortex_breach"
  double fromDepthMm = 0, toDepthMm = 0;
  std::array<double, 3> firstMm{0, 0, 0};
};

struct TrajectoryCheck {
  std::array<double, 3> entryMm{0, 0, 0}, endMm{0, 0, 0};
  double lengthMm = 0, stepMm = 0;
  double reachesVertebraMm = -1; // depth of the first sample in the target vertebra; -1: never
  std::vector<TrajectoryCrossing> crossings; // by depth
  std::string verdict;                       // "clear", "warning", "refused", "unchecked"
  std::string rule;                          // the anatomy's rule ("labels" or "ct-bone-rule")
  std::string message;                       // one line: what the shaft crosses, where, and what to do
  bool refused() const { return verdict == "refused"; }
  nlohmann::json toJson() const;
};

// The shaft from entryMm to endMm through `anatomy`. std::invalid_argument for a zero-length shaft or
// non-finite points.
TrajectoryCheck checkTrajectory(const Anatomy& anatomy, const std::array<double, 3>& entryMm,
                                const std::array<double, 3>& endMm, const TrajectoryOptions& options = {});

} // namespace cementsph::anatomy
