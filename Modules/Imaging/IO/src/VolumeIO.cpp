#include "cementsph/imaging/VolumeIO.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/DicomInput.h"
#include "cementsph/imaging/LibraryMessages.h"

#include "NrrdGzip.h"
#include "VolumeFileChecks.h"

#include <itkGDCMImageIO.h>
#include <itkImageFileReader.h>
#include <itkImageFileWriter.h>
#include <itkImageSeriesReader.h>
#include <itkMetaImageIO.h>
#include <itkNiftiImageIO.h>
#include <itkNrrdImageIO.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <cctype>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace cementsph::imaging {

namespace fs = std::filesystem;

std::array<double, 6> VolumeGeometry::physicalBounds() const {
  std::array<double, 6> b{1e300, -1e300, 1e300, -1e300, 1e300, -1e300};
  for (int corner = 0; corner < 8; ++corner) {
    double idx[3];
    for (int a = 0; a < 3; ++a)
      idx[a] = (corner >> a & 1) ? static_cast<double>(size[a]) - 1.0 : 0.0;
    for (int r = 0; r < 3; ++r) {
      double p = origin[r];
      for (int c = 0; c < 3; ++c) p += direction[3 * r + c] * spacing[c] * idx[c];
      b[2 * r] = std::min(b[2 * r], p);
      b[2 * r + 1] = std::max(b[2 * r + 1], p);
    }
  }
  return b;
}

bool VolumeGeometry::sameGrid(const VolumeGeometry& o, double tol) const {
  if (size != o.size) return false;
  for (int i = 0; i < 3; ++i)
    if (std::abs(origin[i] - o.origin[i]) > tol || std::abs(spacing[i] - o.spacing[i]) > tol)
      return false;
  for (int i = 0; i < 9; ++i)
    if (std::abs(direction[i] - o.direction[i]) > tol) return false;
  return true;
}

VolumeGeometry geometryOf(const itk::ImageBase<3>* image) {
  VolumeGeometry g;
  const auto region = image->GetLargestPossibleRegion();
  for (unsigned i = 0; i < 3; ++i) {
    g.size[i] = region.GetSize()[i];
    g.origin[i] = image->GetOrigin()[i];
    g.spacing[i] = image->GetSpacing()[i];
    for (unsigned j = 0; j < 3; ++j) g.direction[3 * i + j] = image->GetDirection()[i][j];
  }
  return g;
}

double overlapVolumeMm3(const VolumeGeometry& a, const VolumeGeometry& b) {
  const auto ba = a.physicalBounds();
  const auto bb = b.physicalBounds();
  double v = 1.0;
  for (int i = 0; i < 3; ++i) {
    // Voxel centres span the bounds; each voxel reaches half a spacing beyond (axis-aligned approx).
    const double lo = std::max(ba[2 * i] - 0.5 * a.spacing[i], bb[2 * i] - 0.5 * b.spacing[i]);
    const double hi = std::min(ba[2 * i + 1] + 0.5 * a.spacing[i], bb[2 * i + 1] + 0.5 * b.spacing[i]);
    if (hi <= lo) return 0.0;
    v *= hi - lo;
  }
  return v;
}

namespace {

itk::ImageIOBase::Pointer imageIOForExtension(const std::string& path) {
  const std::string ext = fullExtension(path);
  if (ext == ".nrrd" || ext == ".nhdr") return itk::NrrdImageIO::New().GetPointer();
  if (ext == ".mha" || ext == ".mhd") return itk::MetaImageIO::New().GetPointer();
  if (ext == ".nii" || ext == ".nii.gz") return itk::NiftiImageIO::New().GetPointer();
  if (ext == ".dcm") return itk::GDCMImageIO::New().GetPointer();
  return nullptr;
}

// Sane ranges for a CT read from disk: spacings of a micrometre to 10 cm (detail::kMinSpacingMm..), at most
// 2^30 voxels (4 GiB of float). A header outside them is damaged or not a CT; refusing it here keeps a 1e300
// spacing or a 10^12-voxel claim from reaching the registration, the particle model or the allocator.
using detail::kMaxSpacingMm;
using detail::kMaxVoxels;
using detail::kMinSpacingMm;

std::string sizeText(const std::array<std::size_t, 3>& size) {
  return std::to_string(size[0]) + "x" + std::to_string(size[1]) + "x" + std::to_string(size[2]);
}

void checkGeometry(const std::string& path, const std::array<std::size_t, 3>& size, const double* spacing,
                   const double* origin, const double* direction) {
  for (unsigned i = 0; i < 3; ++i)
    if (size[i] < 2) throw std::runtime_error(path + ": not a 3-D volume (size " + sizeText(size) + ")");
  if (double(size[0]) * double(size[1]) * double(size[2]) > kMaxVoxels)
    throw std::runtime_error(path + ": " + sizeText(size) + " voxels is more than this program reads (2^30)");
  for (unsigned i = 0; i < 3; ++i)
    if (!(spacing[i] >= kMinSpacingMm && spacing[i] <= kMaxSpacingMm)) {
      std::ostringstream s;
      s << path << ": voxel spacing " << spacing[i] << " mm is outside " << kMinSpacingMm << ".." << kMaxSpacingMm
        << " mm (damaged header?)";
      throw std::runtime_error(s.str());
    }
  for (unsigned i = 0; i < 3; ++i)
    if (!std::isfinite(origin[i]) || std::abs(origin[i]) > 1e7)
      throw std::runtime_error(path + ": the origin is not a finite position within 10 km (damaged header?)");
  for (unsigned i = 0; i < 9; ++i)
    if (!std::isfinite(direction[i])) throw std::runtime_error(path + ": the direction matrix is not finite");
  // Each axis a unit vector: the readers normalise them, so a longer or shorter one (or one whose length
  // overflowed) is damage. The length is computed without overflow (detail::scaledNorm).
  for (unsigned c = 0; c < 3; ++c) {
    const double axis[3] = {direction[c], direction[3 + c], direction[6 + c]};
    if (!(std::abs(detail::scaledNorm(axis, 3) - 1.0) < 1e-3))
      throw std::runtime_error(path + ": the direction matrix's axis " + std::to_string(c) +
                               " is not a unit vector (damaged header?)");
  }
  double det = direction[0] * (direction[4] * direction[8] - direction[5] * direction[7]) -
               direction[1] * (direction[3] * direction[8] - direction[5] * direction[6]) +
               direction[2] * (direction[3] * direction[7] - direction[4] * direction[6]);
  if (!(std::abs(det) > 1e-6)) throw std::runtime_error(path + ": the direction matrix is singular");
}

void checkVolume(const std::string& path, const ImageType* image) {
  const VolumeGeometry g = geometryOf(image);
  checkGeometry(path, g.size, g.spacing.data(), g.origin.data(), g.direction.data());
  const float* voxels = image->GetBufferPointer();
  const std::size_t n = g.size[0] * g.size[1] * g.size[2];
  for (std::size_t k = 0; k < n; ++k)
    if (!std::isfinite(voxels[k])) {
      const std::size_t x = k % g.size[0], y = k / g.size[0] % g.size[1], z = k / (g.size[0] * g.size[1]);
      throw std::runtime_error(path + ": voxel (" + std::to_string(x) + "," + std::to_string(y) + "," +
                               std::to_string(z) + ") is " + (std::isnan(voxels[k]) ? "NaN" : "infinite") +
                               "; a CT must hold finite values");
    }
}

ImageType::Pointer readDicomSeries(const std::string& directory) {
  // Our own header checks first (DicomInput.h): GDCM aborts the process on some files, and ITK would read
  // a mixed or gappy folder as one volume.
  const std::vector<std::string> files = ctSeriesFiles(directory);
  using Reader = itk::ImageSeriesReader<ImageType>;
  auto reader = Reader::New();
  auto io = itk::GDCMImageIO::New(); // applies Rescale Slope/Intercept: float output is HU
  reader->SetImageIO(io);
  reader->SetFileNames(files);
  StderrCapture quiet;
  reader->Update();
  return reader->GetOutput();
}

detail::VolumeFormat formatOf(const itk::ImageIOBase* io) {
  if (dynamic_cast<const itk::MetaImageIO*>(io)) return detail::VolumeFormat::MetaImage;
  if (dynamic_cast<const itk::NiftiImageIO*>(io)) return detail::VolumeFormat::Nifti;
  return detail::VolumeFormat::Nrrd;
}

// The DICOM preamble: "DICM" at byte 128 (files without it are only recognised by their extension).
bool hasDicomMagic(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {0, 0, 0, 0};
  in.seekg(128);
  in.read(magic, 4);
  return in.gcount() == 4 && std::string(magic, 4) == "DICM";
}

ImageType::Pointer readVolumeFile(const std::string& path) {
  // GDCM is never given a single file: GDCMImageIO's CanReadFile already parses it, and GDCM asserts on
  // some files. A DICOM file is diagnosed from its header instead (a volume is a folder of slices).
  const std::string ext = fullExtension(path);
  if (ext == ".dcm" || ext == ".dicom" || ext == ".ima" || fs::path(path).filename() == "DICOMDIR")
    refuseSingleDicomFile(path);
  itk::ImageIOBase::Pointer io = imageIOForExtension(path);
  if (!io || !io->CanReadFile(path.c_str())) {
    // Unknown extension or content that does not match it: try every format we know.
    io = nullptr;
    const std::vector<itk::ImageIOBase::Pointer> candidates{itk::NrrdImageIO::New().GetPointer(),
                                                            itk::MetaImageIO::New().GetPointer(),
                                                            itk::NiftiImageIO::New().GetPointer()};
    for (const auto& candidate : candidates)
      if (candidate->CanReadFile(path.c_str())) {
        io = candidate;
        break;
      }
  }
  if (!io) {
    if (hasDicomMagic(path)) refuseSingleDicomFile(path);
    throw std::runtime_error(path + ": not a readable image (corrupt, or not DICOM, NRRD, MetaImage or NIfTI)");
  }
  const detail::VolumeFormat format = formatOf(io);
  detail::checkHeaderBeforeItk(path, format);
  std::string messages;
  {
    StderrCapture capture; // MetaIO and nifti_io write their complaints to stderr
    io->SetFileName(path);
    io->ReadImageInformation();
    messages = capture.release();
  }
  // MetaIO's own words (shown with --verbose) name no file and no remedy: ours do.
  if (format == detail::VolumeFormat::MetaImage && !oneLine(messages).empty())
    throw std::runtime_error(path + ": corrupt MetaImage header (the reader could not parse it); check its keys "
                                    "against the MetaImage format or export it again");
  if (io->GetNumberOfDimensions() != 3)
    throw std::runtime_error(path + ": not a 3-D volume (" + std::to_string(io->GetNumberOfDimensions()) +
                             "-D image)");
  if (io->GetNumberOfComponents() != 1)
    throw std::runtime_error(path + ": " + std::to_string(io->GetNumberOfComponents()) +
                             " values per voxel (a colour, vector or 4-D image); a CT has one");
  {
    std::array<std::size_t, 3> size{};
    double spacing[3], origin[3], direction[9];
    for (unsigned i = 0; i < 3; ++i) {
      size[i] = io->GetDimensions(i);
      spacing[i] = io->GetSpacing(i);
      origin[i] = io->GetOrigin(i);
      for (unsigned j = 0; j < 3; ++j) direction[3 * j + i] = io->GetDirection(i)[j];
    }
    checkGeometry(path, size, spacing, origin, direction);
  }
  detail::checkPayload(path, format, io->GetImageSizeInBytes());
  auto reader = itk::ImageFileReader<ImageType>::New();
  reader->SetImageIO(io);
  reader->SetFileName(path);
  {
    StderrCapture capture;
    reader->Update();
    messages = capture.release();
  }
  // MetaIO reports a short read only on stderr ("data not read completely"): anything it says is an error.
  if (format == detail::VolumeFormat::MetaImage && !oneLine(messages).empty())
    throw std::runtime_error(path + ": corrupt or truncated MetaImage (its data could not be read completely); "
                                    "export it again");
  return reader->GetOutput();
}

} // namespace

ImageType::Pointer readVolume(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw std::runtime_error(path + ": no such file or directory");
  // A pipe, device or socket is refused before anything opens it: opening a FIFO with no writer blocks forever
  // (`--ct fifo.nrrd` hung), and /dev/zero never ends.
  if (!fs::is_directory(path, ec) && !fs::is_regular_file(path, ec))
    throw std::runtime_error(path + ": not a regular file (a pipe, device or socket); give a volume file (.nrrd, .mha, "
                                    ".nii, .nii.gz) or a DICOM folder");
  ImageType::Pointer image;
  try {
    image = fs::is_directory(path, ec) ? readDicomSeries(path) : readVolumeFile(path);
  } catch (const itk::ExceptionObject& e) {
    // ITK's description carries source paths and object addresses: only --verbose shows it.
    if (libraryMessagesVerbose()) std::cerr << oneLine(e.GetDescription()) << "\n";
    throw std::runtime_error(path + ": cannot read (corrupt or truncated, or not a volume this program reads); "
                                    "export it again as NRRD, MetaImage or NIfTI");
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(path + ": not enough memory to read it");
  }
  checkVolume(path, image);
  image->DisconnectPipeline();
  return image;
}

namespace {

// The gzip NRRD path writes the buffer's bytes as they are: NRRD's "endian: little" holds only on such a machine.
constexpr bool kLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

template <typename TImage> void writeImage(const TImage* image, const std::string& path, bool compress = true) {
  if (!image) throw std::runtime_error(path + ": nothing to write");
  if (!imageIOForExtension(path) || fullExtension(path) == ".dcm")
    throw std::runtime_error(path + ": unknown output format (use .nrrd, .mha, .nii or .nii.gz)");
  // A compressed .nrrd on a little-endian machine: the header ITK would write, and the voxels' bytes deflated by
  // libdeflate (a third of the time ITK's zlib takes on a CT; NrrdGzip.h).
  const bool gzipHere = compress && fullExtension(path) == ".nrrd" && kLittleEndian &&
                        image->GetBufferedRegion() == image->GetLargestPossibleRegion();
  writeAtomically(path, [&](const std::string& tmp) {
    if (gzipHere) {
      using Pixel = typename TImage::PixelType;
      static_assert(std::is_same_v<Pixel, float> || std::is_same_v<Pixel, std::uint8_t>, "a volume (float) or a mask (uint8)");
      const auto size = image->GetLargestPossibleRegion().GetSize();
      const std::array<std::size_t, 3> voxels{std::size_t(size[0]), std::size_t(size[1]), std::size_t(size[2])};
      const auto& d = image->GetDirection();
      std::array<double, 9> direction{};
      for (unsigned r = 0; r < 3; ++r)
        for (unsigned c = 0; c < 3; ++c) direction[3 * r + c] = d[r][c];
      const std::string header = detail::gzipNrrdHeader(
          std::is_same_v<Pixel, float> ? "float" : "unsigned char", sizeof(Pixel) > 1,
          voxels, direction,
          {image->GetSpacing()[0], image->GetSpacing()[1], image->GetSpacing()[2]},
          {image->GetOrigin()[0], image->GetOrigin()[1], image->GetOrigin()[2]});
      detail::writeGzipNrrd(tmp, header, image->GetBufferPointer(), voxels[0] * voxels[1] * voxels[2] * sizeof(Pixel));
      return;
    }
    auto writer = itk::ImageFileWriter<TImage>::New();
    writer->SetImageIO(imageIOForExtension(path));
    writer->SetFileName(tmp);
    writer->SetInput(image);
    writer->SetUseCompression(compress);
    try {
      writer->Update();
    } catch (const itk::ExceptionObject& e) {
      if (libraryMessagesVerbose()) std::cerr << oneLine(e.GetDescription()) << "\n"; // ITK's words: --verbose only
      throw std::runtime_error("cannot write (disk full, file size limit or no permission?)");
    }
  });
}

} // namespace

void writeVolume(const ImageType* image, const std::string& path, bool compress) { writeImage(image, path, compress); }
void writeMask(const MaskType* mask, const std::string& path) { writeImage(mask, path); }

} // namespace cementsph::imaging
