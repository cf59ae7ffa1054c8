// Leaked cement by where it went (issue 20, item 1): cement outside the target vertebra, grouped into sites.
//
// A voxel holds cement volume fill x porosity x voxel volume (fill: the fraction of its pore space filled).
// Leakage is that volume in every voxel not classed TargetVertebra. A site is a 26-connected set of leaked voxels
// of one leak kind: disc (Disc), canal (Canal), venous (Vessel: paravertebral or epidural veins, the aorta),
// other_bone (OtherBone: a neighbour reached through the disc or a joint), cortex_breach (OtherSoftTissue and Air:
// cement through the cortex into the tissue around). Its first time is the earliest arrival among its voxels
// (arrival < 0 or NaN: not known), its position the cement-weighted centroid.
#pragma once

#include "cementsph/anatomy/VertebraAnatomy.h"

#include <nlohmann/json.hpp>

#include <array>
#include <map>
#include <string>
#include <vector>

namespace cementsph::anatomy {

const char* leakKind(TissueClass c); // "disc", "canal", "venous", "other_bone", "cortex_breach"; "" for the target

struct LeakSite {
  std::string kind;
  TissueClass tissue = TissueClass::OtherSoftTissue;
  double volumeMl = 0.0;
  double firstTimeS = -1.0; // -1: not known
  std::array<double, 3> positionMm{0, 0, 0};
  std::size_t voxels = 0;
};

struct LeakReport {
  std::vector<LeakSite> sites;             // largest first
  std::map<std::string, double> volumeMlByKind; // every kind, 0 where none
  std::map<std::string, int> sitesByKind;
  double leakedMl = 0.0;                   // all cement outside the target vertebra
  double insideMl = 0.0;                   // cement in the target vertebra
  std::string rule;                        // the anatomy's rule ("labels" or "ct-bone-rule")
  nlohmann::json toJson() const;
};

struct LeakOptions {
  double minFill = 1e-6; // a voxel with less fill holds no cement (round-off of the fill field)
};

// fill, arrivalS, porosity: one value per voxel of anatomy.grid (porosity empty: 1 everywhere; arrivalS empty:
// times not known). std::invalid_argument when a size differs from the grid's.
LeakReport classifyLeaks(const Anatomy& anatomy, const std::vector<double>& fill, const std::vector<double>& arrivalS,
                         const std::vector<double>& porosity, const LeakOptions& options = {});

} // namespace cementsph::anatomy
