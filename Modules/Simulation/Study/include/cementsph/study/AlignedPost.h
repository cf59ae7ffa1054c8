// A post-operative CT put on the pre-operative CT's grid, as the paper compares them (Basafa et al. 2013:
// post-operative CT registered to the pre-operative one before the cement is segmented): affine
// registration with the cement kept out of the metric (AffineRegistration.h), then resampling; or, when
// the scans are already aligned, resampling alone. Shared by `cementsph compare` and `cementsph study`.
#pragma once

#include "cementsph/imaging/AffineRegistration.h"
#include "cementsph/imaging/ImageTypes.h"

#include <optional>

namespace cementsph::study {

struct AlignedPost {
  imaging::ImageType::Pointer volume;                    // post on pre's grid (outside: air)
  std::optional<imaging::RegistrationResult> registration; // absent without registration
};

// Throws std::runtime_error if, without registration, the two volumes do not overlap in space.
AlignedPost alignPostOntoPre(const imaging::ImageType* pre, const imaging::ImageType* post, bool registration,
                             const imaging::RegistrationOptions& options = {});

} // namespace cementsph::study
