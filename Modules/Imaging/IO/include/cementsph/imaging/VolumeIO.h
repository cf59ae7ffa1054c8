// Reading and writing CT volumes with their geometry (origin, spacing, direction, in mm).
// Formats: a DICOM series (a directory; HU through rescale slope/intercept), NRRD (.nrrd, .nhdr,
// the default output), MetaImage (.mha, .mhd) and NIfTI (.nii, .nii.gz).
// Every problem is a std::runtime_error whose message starts with the path.
#pragma once

#include "cementsph/imaging/ImageTypes.h"

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace cementsph::imaging {

// The geometry of a volume: what must survive every read, register, resample and write.
struct VolumeGeometry {
  std::array<std::size_t, 3> size{};
  std::array<double, 3> origin{};    // physical position of voxel (0,0,0), mm
  std::array<double, 3> spacing{};   // mm
  std::array<double, 9> direction{}; // row-major; columns are the index axes in physical space

  // Axis-aligned physical bounding box of the voxel centres, mm: {xmin,xmax,ymin,ymax,zmin,zmax}.
  std::array<double, 6> physicalBounds() const;
  bool sameGrid(const VolumeGeometry& other, double tolerance = 1e-4) const;
};

VolumeGeometry geometryOf(const itk::ImageBase<3>* image);

// Volume of the intersection of the two physical bounding boxes, in mm^3 (0 when disjoint).
double overlapVolumeMm3(const VolumeGeometry& a, const VolumeGeometry& b);

// path: a directory (DICOM series; the series with the most files if there are several) or a file
// chosen by its extension. Throws for a missing path, an unreadable or truncated file, or an image
// that is not a 3-D volume (fewer than 2 slices along any axis).
ImageType::Pointer readVolume(const std::string& path);

// Writes atomically (temporary sibling, then rename). The format follows the extension; a path
// without a known extension is an error (NRRD is what the applications choose by default).
// compress: deflate the data (NRRD gzip, MetaImage zlib); off for small images written on a hot path (a
// DRR: deflating a 512^2 float image costs more than its bytes save).
void writeVolume(const ImageType* image, const std::string& path, bool compress = true);
void writeMask(const MaskType* mask, const std::string& path);

// Writes a DICOM series (one file per slice, int16, CT modality) into directory, which is created.
// Stored values are HU - rescaleInterceptHU (scanners commonly store with intercept -1024); the
// Rescale Intercept tag says so. Geometry goes into Image Position / Orientation Patient.
// The slices go to a staging folder beside directory and move in only when all are written (an earlier
// series' slices go first): a failure (no room, the file size limit, a failed write) is an OutputError of
// one line and leaves no slice behind.
void writeDicomSeries(const ImageType* image, const std::string& directory,
                      double rescaleInterceptHU = 0.0);

// How writeDicomSeries asks for the room left where it writes: bytes free to this user on the filesystem
// holding `folder` (statvfs: f_bavail x f_frsize), or std::nullopt when that cannot be told (then the check
// is skipped and a failed write is still caught after). Replaceable, so that a test reaches the "not enough
// room" refusal without filling a disk; an empty query restores statvfs. Returns the query it replaced.
using FreeSpaceQuery = std::function<std::optional<std::uintmax_t>(const std::string& folder)>;
FreeSpaceQuery setFreeSpaceQuery(FreeSpaceQuery query);

} // namespace cementsph::imaging
