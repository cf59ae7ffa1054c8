#include "cementsph/drr/XraySequenceComparison.h"

#include "cementsph/surfacemetrics/VolumeMetrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>

namespace cementsph::drr {

std::size_t XrayComparison::matched() const {
  return static_cast<std::size_t>(
      std::count_if(pairs.begin(), pairs.end(), [](const XrayFramePair& p) { return p.frame && p.reference; }));
}

double defaultMatchToleranceS(const XraySequence& a, const XraySequence& b) {
  double shortest = std::numeric_limits<double>::infinity();
  for (const XraySequence* s : {&a, &b})
    for (std::size_t k = 1; k < s->frames().size(); ++k)
      shortest = std::min(shortest, s->frames()[k].timeS - s->frames()[k - 1].timeS);
  return 0.5 * shortest;
}

XrayComparison compareXraySequences(const XraySequence& a, const XraySequence& b, std::optional<double> toleranceS) {
  const DRRGeometry &ga = a.options().geometry, &gb = b.options().geometry;
  if (ga.rows != gb.rows || ga.cols != gb.cols || std::abs(ga.pixelWidthMm() - gb.pixelWidthMm()) > 1e-9 ||
      std::abs(ga.pixelHeightMm() - gb.pixelHeightMm()) > 1e-9)
    throw std::invalid_argument("the two X-ray sequences have different detectors");
  XrayComparison c;
  c.toleranceS = toleranceS ? *toleranceS : defaultMatchToleranceS(a, b);
  if (!(c.toleranceS >= 0.0)) throw std::invalid_argument("the time-matching tolerance must be 0 s or more");

  // Candidate pairs within the tolerance, closest first (ties: earlier frames first); greedy one-to-one.
  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < a.frames().size(); ++i)
    for (std::size_t j = 0; j < b.frames().size(); ++j) {
      const double dt = std::abs(a.frames()[i].timeS - b.frames()[j].timeS);
      if (dt <= c.toleranceS) candidates.emplace_back(dt, i, j);
    }
  std::sort(candidates.begin(), candidates.end());
  std::vector<std::optional<std::size_t>> partnerOfA(a.frames().size()), partnerOfB(b.frames().size());
  for (const auto& [dt, i, j] : candidates)
    if (!partnerOfA[i] && !partnerOfB[j]) {
      partnerOfA[i] = j;
      partnerOfB[j] = i;
    }

  for (std::size_t i = 0; i < a.frames().size(); ++i) {
    XrayFramePair p;
    p.timeS = a.frames()[i].timeS;
    p.frame = i;
    p.reference = partnerOfA[i];
    if (p.reference) {
      const auto o = surfacemetrics::overlap(a.frames()[i].cementMask, b.frames()[*p.reference].cementMask);
      p.dice = o.dice;
      p.iou = o.jaccard;
    }
    c.pairs.push_back(p);
  }
  for (std::size_t j = 0; j < b.frames().size(); ++j)
    if (!partnerOfB[j]) {
      XrayFramePair p;
      p.timeS = b.frames()[j].timeS;
      p.reference = j;
      c.pairs.push_back(p);
    }
  std::stable_sort(c.pairs.begin(), c.pairs.end(),
                   [](const XrayFramePair& x, const XrayFramePair& y) { return x.timeS < y.timeS; });
  return c;
}

} // namespace cementsph::drr
