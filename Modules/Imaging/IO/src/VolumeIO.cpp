#include "cementsph/imaging/VolumeIO.h"

#include "cementsph/imaging/AtomicFile.h"

#include <itkGDCMImageIO.h>
#include <itkGDCMSeriesFileNames.h>
#include <itkImageFileReader.h>
#include <itkImageFileWriter.h>
#include <itkImageSeriesReader.h>
#include <itkMetaImageIO.h>
#include <itkNiftiImageIO.h>
#include <itkNrrdImageIO.h>

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cctype>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
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

void checkVolume(const std::string& path, const ImageType* image) {
  const auto size = image->GetLargestPossibleRegion().GetSize();
  for (unsigned i = 0; i < 3; ++i)
    if (size[i] < 2)
      throw std::runtime_error(path + ": not a 3-D volume (size " + std::to_string(size[0]) + "x" +
                               std::to_string(size[1]) + "x" + std::to_string(size[2]) + ")");
  for (unsigned i = 0; i < 3; ++i)
    if (!(image->GetSpacing()[i] > 0.0))
      throw std::runtime_error(path + ": non-positive voxel spacing");
}

ImageType::Pointer readDicomSeries(const std::string& directory) {
  auto names = itk::GDCMSeriesFileNames::New();
  names->SetUseSeriesDetails(true);
  names->SetDirectory(directory);
  const auto& uids = names->GetSeriesUIDs();
  if (uids.empty()) throw std::runtime_error(directory + ": directory holds no DICOM series");
  // Several series: take the one with the most slices (the volume, not a scout).
  std::vector<std::string> files;
  for (const auto& uid : uids) {
    auto candidate = names->GetFileNames(uid);
    if (candidate.size() > files.size()) files = candidate;
  }
  if (files.size() < 2)
    throw std::runtime_error(directory + ": DICOM series has " + std::to_string(files.size()) +
                             " slice(s); a 3-D volume needs at least 2");
  using Reader = itk::ImageSeriesReader<ImageType>;
  auto reader = Reader::New();
  auto io = itk::GDCMImageIO::New(); // applies Rescale Slope/Intercept: float output is HU
  reader->SetImageIO(io);
  reader->SetFileNames(files);
  reader->Update();
  return reader->GetOutput();
}

// ITK reports a truncated NRRD, but reads truncated NIfTI files without an error (nifti_io only
// prints to stderr) and MetaIO only prints "data not read completely" to std::cerr. So: NIfTI is
// checked for size (gzip streams are decompressed to the end, which also catches a corrupt stream),
// and MetaImage reads run with std::cerr captured; anything MetaIO says is taken as an error.
constexpr std::uintmax_t kNiftiHeaderBytes = 348;

void checkNiftiComplete(const std::string& path, std::uintmax_t imageBytes) {
  const std::string ext = fullExtension(path);
  std::uintmax_t available = 0;
  if (ext == ".nii") {
    available = fs::file_size(path);
  } else if (ext == ".nii.gz") {
    gzFile gz = gzopen(path.c_str(), "rb");
    if (!gz) throw std::runtime_error(path + ": cannot open");
    std::vector<char> buffer(1 << 16);
    int n = 0;
    while ((n = gzread(gz, buffer.data(), static_cast<unsigned>(buffer.size()))) > 0)
      available += static_cast<std::uintmax_t>(n);
    int code = Z_OK;
    const std::string message = n < 0 ? gzerror(gz, &code) : "";
    gzclose(gz);
    if (n < 0) throw std::runtime_error(path + ": corrupt or truncated gzip stream: " + message);
  } else {
    return;
  }
  if (available < imageBytes + kNiftiHeaderBytes)
    throw std::runtime_error(path + ": truncated (" + std::to_string(available) + " bytes of data, "
                             "at least " + std::to_string(imageBytes + kNiftiHeaderBytes) +
                             " expected)");
}

// Redirects std::cerr into a string for its lifetime (not thread-safe: reads are sequential here).
class CerrCapture {
public:
  CerrCapture() : old_(std::cerr.rdbuf(captured_.rdbuf())) {}
  ~CerrCapture() { std::cerr.rdbuf(old_); }
  CerrCapture(const CerrCapture&) = delete;
  CerrCapture& operator=(const CerrCapture&) = delete;
  std::string text() const { return captured_.str(); }

private:
  std::ostringstream captured_;
  std::streambuf* old_;
};

} // namespace

ImageType::Pointer readVolume(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw std::runtime_error(path + ": no such file or directory");
  ImageType::Pointer image;
  try {
    if (fs::is_directory(path, ec)) {
      image = readDicomSeries(path);
    } else {
      itk::ImageIOBase::Pointer io = imageIOForExtension(path);
      if (!io || !io->CanReadFile(path.c_str())) {
        // Unknown extension or content that does not match it: try every format we know.
        io = nullptr;
        const std::vector<itk::ImageIOBase::Pointer> candidates{
            itk::NrrdImageIO::New().GetPointer(), itk::MetaImageIO::New().GetPointer(),
            itk::NiftiImageIO::New().GetPointer(), itk::GDCMImageIO::New().GetPointer()};
        for (const auto& candidate : candidates) {
          if (candidate->CanReadFile(path.c_str())) {
            io = candidate;
            break;
          }
        }
      }
      if (!io)
        throw std::runtime_error(path + ": not a readable image (corrupt, or not DICOM, NRRD, "
                                        "MetaImage or NIfTI)");
      io->SetFileName(path);
      io->ReadImageInformation();
      if (io->GetNumberOfDimensions() != 3)
        throw std::runtime_error(path + ": not a 3-D volume (" +
                                 std::to_string(io->GetNumberOfDimensions()) + "-D image)");
      checkNiftiComplete(path, io->GetImageSizeInBytes());
      auto reader = itk::ImageFileReader<ImageType>::New();
      reader->SetImageIO(io);
      reader->SetFileName(path);
      const bool isMeta = dynamic_cast<itk::MetaImageIO*>(io.GetPointer()) != nullptr;
      std::string metaMessages;
      {
        std::unique_ptr<CerrCapture> capture;
        if (isMeta) capture = std::make_unique<CerrCapture>();
        reader->Update();
        if (capture) metaMessages = capture->text();
      }
      if (!metaMessages.empty()) {
        while (!metaMessages.empty() && std::isspace(static_cast<unsigned char>(metaMessages.back())))
          metaMessages.pop_back();
        for (auto& ch : metaMessages)
          if (ch == '\n') ch = ' ';
        throw std::runtime_error(path + ": corrupt or truncated MetaImage (" + metaMessages + ")");
      }
      image = reader->GetOutput();
    }
  } catch (const itk::ExceptionObject& e) {
    throw std::runtime_error(path + ": cannot read (corrupt or truncated?): " + e.GetDescription());
  }
  checkVolume(path, image);
  image->DisconnectPipeline();
  return image;
}

namespace {

template <typename TImage> void writeImage(const TImage* image, const std::string& path) {
  if (!image) throw std::runtime_error(path + ": nothing to write");
  if (!imageIOForExtension(path) || fullExtension(path) == ".dcm")
    throw std::runtime_error(path + ": unknown output format (use .nrrd, .mha, .nii or .nii.gz)");
  writeAtomically(path, [&](const std::string& tmp) {
    auto writer = itk::ImageFileWriter<TImage>::New();
    writer->SetImageIO(imageIOForExtension(path));
    writer->SetFileName(tmp);
    writer->SetInput(image);
    writer->SetUseCompression(true);
    try {
      writer->Update();
    } catch (const itk::ExceptionObject& e) {
      throw std::runtime_error(std::string("cannot write: ") + e.GetDescription());
    }
  });
}

} // namespace

void writeVolume(const ImageType* image, const std::string& path) { writeImage(image, path); }
void writeMask(const MaskType* mask, const std::string& path) { writeImage(mask, path); }

} // namespace cementsph::imaging
