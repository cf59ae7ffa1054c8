// The gzip-encoded NRRD volumes this module writes (writeVolume, writeMask to .nrrd), compressed with
// libdeflate instead of ITK's writer (Teem's zlib at level 2). The header is the one ITK's NRRD writer gives
// these images, field for field and in its order (ImagingIOTest's NrrdGzip.* compare the two); the payload
// is one standard gzip member of the voxels' bytes, so every NRRD reader reads it. (Lines ITK would copy from
// an image's metadata dictionary, `key:=value`, are not written; the simulated CTs and label maps ITK wrote
// before held none.)
//
// Why: on a CT the payload is float noise that deflates slowly, and the simulated CT's compression was the
// largest single cost of an injection on a clinical-size scan (0.86 s of 3.0 s on a 200 x 200 x 188 CT, the
// injection loop 1.17 s; docs/benchmark-history.md, "What changed in session 10"). libdeflate's level 1 on that payload:
// 0.25 s and 12.4 MB, against zlib's level 2 (ITK's) 0.85 s and 13.1 MB.
//
// The header is written here rather than taken from a raw file ITK writes first: that file (the voxels
// uncompressed) would need room the compressed one does not, under a file size limit or on a nearly full disk.
#pragma once

#include <array>
#include <cstddef>
#include <string>

namespace cementsph::imaging::detail {

// The header of a 3-D NRRD in LPS space with gzip-encoded attached data, as ITK's NrrdImageIO writes it:
// type ("float", "unsigned char"), sizes, the space directions (column a: direction's column a times
// spacing a), kinds domain, endian little for multi-byte types, space origin; doubles to 17 digits.
std::string gzipNrrdHeader(const char* type, bool multiByte, const std::array<std::size_t, 3>& size,
                           const std::array<double, 9>& directionRowMajor, const std::array<double, 3>& spacing,
                           const std::array<double, 3>& origin);

// Writes header and then the gzip member of the bytes (libdeflate, level 1) to path. Throws
// std::runtime_error (naming no path: the caller's atomic write names it) if it cannot.
void writeGzipNrrd(const std::string& path, const std::string& header, const void* bytes, std::size_t count);

} // namespace cementsph::imaging::detail
