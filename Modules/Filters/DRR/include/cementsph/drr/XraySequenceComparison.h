// Two X-ray sequences compared frame by frame, as the paper's Fig. 12 (Basafa et al. 2013) compares the
// simulated cement with the C-arm's: frames are matched by time, and for each matched pair the cement
// masks' Dice and IoU (Jaccard) are computed; the projected areas over time come from each sequence.
//
// Matching: every candidate pair (frame of a, frame of b) with |t_a - t_b| <= tolerance is considered,
// closest first, and a pair is kept when neither frame is already matched, so each frame is matched at
// most once. Default tolerance: half the shortest interval between consecutive frames of either sequence
// (so a frame can only match its own instant); infinite when both sequences have a single frame.
// Overlap of two masks as cementsph::surfacemetrics::overlap: Dice = 2|A&B| / (|A| + |B|),
// IoU = |A&B| / |A|B|, both 1 when both masks are empty (frame 0 of each sequence, for instance).
#pragma once

#include "cementsph/drr/XraySequence.h"

#include <cstddef>
#include <optional>
#include <vector>

namespace cementsph::drr {

struct XrayFramePair {
  double timeS = 0.0;                   // the frame's time in a, or b's when only b has this frame
  std::optional<std::size_t> frame;     // index in a (none: a frame of b that matched nothing)
  std::optional<std::size_t> reference; // index in b (none: a frame of a that matched nothing)
  std::optional<double> dice, iou;      // when both are present
};

struct XrayComparison {
  double toleranceS = 0.0;
  std::vector<XrayFramePair> pairs; // every frame of a and of b once, in time order
  std::size_t matched() const;
};

// Half the shortest interval between consecutive frames of a or b; +inf when neither has two frames.
double defaultMatchToleranceS(const XraySequence& a, const XraySequence& b);

// Throws std::invalid_argument if the sequences' detectors differ (rows, cols or pixel size) or the
// tolerance is negative or NaN.
XrayComparison compareXraySequences(const XraySequence& a, const XraySequence& b,
                                    std::optional<double> toleranceS = std::nullopt);

} // namespace cementsph::drr
