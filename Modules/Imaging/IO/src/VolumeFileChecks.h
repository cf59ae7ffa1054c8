// Checks on a volume file's own structure, made before ITK reads its pixels, for what ITK's readers do
// not check or crash on: a MetaImage header without its ElementDataFile key (MetaIO then overruns a
// buffer and the C library aborts the process), compressed data that is corrupt or cut short (ITK's NRRD
// reader never looks at the gzip checksum; NIfTI's reader and MetaIO only print to stderr), and headers
// that claim more voxels than the file can hold. Each throws std::runtime_error starting with the path.
#pragma once

#include <cstdint>
#include <string>

namespace cementsph::imaging::detail {

enum class VolumeFormat { Nrrd, MetaImage, Nifti };

// Before ReadImageInformation: a header that would crash the reader.
void checkHeaderBeforeItk(const std::string& path, VolumeFormat format);

// After ReadImageInformation, before the pixels: the data (decompressed to its end, so a checksum
// is verified) must hold imageBytes.
void checkPayload(const std::string& path, VolumeFormat format, std::uintmax_t imageBytes);

} // namespace cementsph::imaging::detail
