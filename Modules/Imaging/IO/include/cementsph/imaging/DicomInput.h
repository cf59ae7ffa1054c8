// Checks on DICOM input before any pixel is read. GDCM asserts (aborts the process) on some files it
// does not expect, among them RT dose grids, DICOMDIR indexes and headers with flipped bytes; and ITK
// reads whatever a folder holds as one volume (an MR series, an RGB picture, a series with a slice
// missing or doubled) with the rescale applied as if it were HU. So the headers are read first, with
// gdcm::Reader stopping before the pixel data, and a series is accepted only when it is one CT volume:
// one series UID, modality CT, one grey sample per pixel, one frame per file, pixel data present, the same
// rows, columns, pixel spacing and orientation in every slice, and slice positions along the normal that
// are distinct and evenly spaced. Every refusal is a std::runtime_error naming the file or folder.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace cementsph::imaging {

struct DicomHeader {
  std::string path;
  std::string mediaStorageSopClass; // (0002,0002); "1.2.840.10008.1.3.10" is a DICOMDIR
  std::string sopClass, seriesUid, modality, photometric;
  int samplesPerPixel = 0, frames = 1, rows = 0, columns = 0, bitsAllocated = 0;
  int bitsStored = 0, highBit = -1; // (0028,0101), (0028,0102); 0 and -1 when absent
  bool hasPixelData = false;
  // Uncompressed pixel data: the element's length and what rows x columns x samples x bytes x frames need.
  std::uintmax_t pixelDataBytes = 0, pixelDataBytesNeeded = 0;
  std::string rescaleSlope, rescaleIntercept; // (0028,1053), (0028,1052) as written; empty when absent
  std::optional<std::array<double, 3>> position;    // Image Position (Patient), mm
  std::optional<std::array<double, 6>> orientation; // Image Orientation (Patient): row, column cosines
  std::optional<std::array<double, 2>> pixelSpacing; // mm: between rows, between columns

  bool isDicomDir() const;
};

// The header of one file, pixel data not read; nullopt when the file is not DICOM at all.
std::optional<DicomHeader> readDicomHeader(const std::string& path);

// Why this slice cannot be part of a CT volume read as HU (empty: it can).
std::string ctSliceProblem(const DicomHeader& header);

// The files of the one CT series in directory, ordered along the slice normal; throws (naming the folder
// and the problem) unless they make one consistent volume. Files that are not DICOM, and DICOMDIR
// indexes, are ignored; series of a single file (scouts, dose reports) beside the volume are ignored.
std::vector<std::string> ctSeriesFiles(const std::string& directory);

// A single DICOM file given where a volume is expected: always throws, with the reason (a DICOMDIR, not
// CT, a multi-frame file, or one slice of a series whose folder should be given instead).
[[noreturn]] void refuseSingleDicomFile(const std::string& path);

} // namespace cementsph::imaging
