// Checks on a volume file's own structure, made before ITK reads it, for what ITK's readers do not check or
// crash on. The readers trust their headers: MetaIO loops on NDims = -1, divides by a pattern's step 0 and
// takes a file name pattern as a printf format; ITK asserts on a NaN NIfTI sform; NaN, infinite or zero
// spacings become 1 mm silently; nifti_io reads past the end as zeros; ITK's NRRD reader never looks at the
// gzip checksum. So every header is parsed and checked here first, and only a header that passes reaches the
// library. Each check throws std::runtime_error: one line, starting with the path, naming the key.
#pragma once

#include <cstdint>
#include <string>

namespace cementsph::imaging::detail {

enum class VolumeFormat { Nrrd, MetaImage, Nifti };

// Sane spacings for a CT read from disk: a micrometre to 10 cm. Outside them a header is damaged or not a CT.
constexpr double kMinSpacingMm = 1e-3, kMaxSpacingMm = 100.0;
// At most 2^30 voxels (4 GiB of float): checked from the header too, before any data is decompressed.
constexpr double kMaxVoxels = 1073741824.0;

// Before CanReadFile's reader sees more than the magic and before ReadImageInformation: a header that would
// crash, hang or mislead the reader.
void checkHeaderBeforeItk(const std::string& path, VolumeFormat format);

// After ReadImageInformation, before the pixels: the data (decompressed to its end, so a checksum
// is verified; every gzip member) must hold imageBytes.
void checkPayload(const std::string& path, VolumeFormat format, std::uintmax_t imageBytes);

// A header value for a message: quoted, at most 40 characters (a damaged header can hold megabytes in one
// value), control characters shown as '?' so the message stays one line.
std::string shownValue(const std::string& value);

// The Euclidean norm without overflow or underflow: scaled by the largest component, so [1e200, 1e200, 0]
// has norm 1.41e200, not inf (and a direction normalised by it is not zero).
double scaledNorm(const double* v, int n);

} // namespace cementsph::imaging::detail
