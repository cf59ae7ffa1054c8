// writeDicomSeries: one int16 CT slice per file with the geometry in Image Position / Orientation
// Patient, following ITK's ResampleDICOM example (per-slice dictionaries, one study/series UID).
// The series is written into a staging folder and moved into place whole (StagedFolder.h): a failed write
// leaves no partial series, and an earlier, longer series' slices do not mix with this one's.
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/LibraryMessages.h"
#include "cementsph/imaging/StagedFolder.h"

#include <sys/resource.h>
#include <sys/statvfs.h>

#include <itkGDCMImageIO.h>
#include <itkImageRegionConstIterator.h>
#include <itkImageRegionIterator.h>
#include <itkImageSeriesWriter.h>
#include <itkMetaDataObject.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>

namespace cementsph::imaging {

namespace {
// A DICOM UID under the UUID-derived root 2.25 (ISO/IEC 9834-8): "2.25." and up to 38 random
// decimal digits, no leading zero; well under the 64-character limit.
class UidGenerator {
public:
  std::string Generate() {
    std::uniform_int_distribution<int> digit(0, 9), first(1, 9);
    std::string uid = "2.25." + std::to_string(first(rng_));
    for (int i = 0; i < 36; ++i) uid += static_cast<char>('0' + digit(rng_));
    return uid;
  }

private:
  std::mt19937_64 rng_{std::random_device{}()};
};

std::optional<std::uintmax_t> statvfsFreeBytes(const std::string& folder) {
  struct statvfs fsInfo {};
  if (statvfs(folder.c_str(), &fsInfo) != 0) return std::nullopt;
  return std::uintmax_t(fsInfo.f_bavail) * fsInfo.f_frsize;
}

FreeSpaceQuery& freeSpaceQuery() {
  static FreeSpaceQuery query = statvfsFreeBytes;
  return query;
}
} // namespace

FreeSpaceQuery setFreeSpaceQuery(FreeSpaceQuery query) {
  FreeSpaceQuery previous = freeSpaceQuery();
  freeSpaceQuery() = query ? std::move(query) : FreeSpaceQuery(statvfsFreeBytes);
  return previous;
}

void writeDicomSeries(const ImageType* image, const std::string& directory, double rescaleInterceptHU) {
  namespace fs = std::filesystem;
  using ShortImage = itk::Image<std::int16_t, 3>;
  using SliceImage = itk::Image<std::int16_t, 2>;
  fs::path target = fs::path(directory).lexically_normal();
  if (target.filename().empty()) target = target.parent_path(); // "dir/series/" names "dir/series"
  std::optional<StagedFolder> staging;
  try {
    staging.emplace(target);
  } catch (const std::exception&) {
    throw OutputError(directory + ": cannot create the folder for the DICOM series (no permission, or a file in "
                                  "the way?); choose another folder");
  }
  StagedFolder& staged = *staging;

  // HU as int16 (rounded, clamped). GDCMImageIO applies the inverse of the Rescale Slope/Intercept
  // found in the dictionary on write (ITK 4.7 migration note "Apply Rescale Slope / Intercept On
  // Write"): it stores HU - intercept itself. Measured: subtracting here too shifted the values.
  auto hu = ShortImage::New();
  hu->CopyInformation(image);
  hu->SetRegions(image->GetLargestPossibleRegion());
  hu->Allocate();
  itk::ImageRegionConstIterator<ImageType> in(image, image->GetLargestPossibleRegion());
  itk::ImageRegionIterator<ShortImage> out(hu, hu->GetLargestPossibleRegion());
  for (; !in.IsAtEnd(); ++in, ++out)
    out.Set(static_cast<std::int16_t>(std::clamp(std::lround(in.Get()), -32768L, 32767L)));

  const auto size = image->GetLargestPossibleRegion().GetSize();
  const auto dir = image->GetDirection();
  UidGenerator uid;
  const std::string study = uid.Generate();
  const std::string series = uid.Generate();
  const std::string frame = uid.Generate();
  auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6f", v);
    return std::string(buf);
  };
  std::ostringstream iop;
  iop << num(dir[0][0]) << "\\" << num(dir[1][0]) << "\\" << num(dir[2][0]) << "\\"
      << num(dir[0][1]) << "\\" << num(dir[1][1]) << "\\" << num(dir[2][1]);

  std::vector<itk::MetaDataDictionary> dictionaries(size[2]);
  std::vector<std::string> files(size[2]);
  for (unsigned z = 0; z < size[2]; ++z) {
    auto& d = dictionaries[z];
    ShortImage::PointType p;
    hu->TransformIndexToPhysicalPoint({{0, 0, static_cast<long>(z)}}, p);
    const std::string ipp = num(p[0]) + "\\" + num(p[1]) + "\\" + num(p[2]);
    itk::EncapsulateMetaData<std::string>(d, "0008|0060", "CT");
    itk::EncapsulateMetaData<std::string>(d, "0008|0016", "1.2.840.10008.5.1.4.1.1.2");
    itk::EncapsulateMetaData<std::string>(d, "0008|0018", uid.Generate());
    itk::EncapsulateMetaData<std::string>(d, "0020|000d", study);
    itk::EncapsulateMetaData<std::string>(d, "0020|000e", series);
    itk::EncapsulateMetaData<std::string>(d, "0020|0052", frame);
    itk::EncapsulateMetaData<std::string>(d, "0020|0013", std::to_string(z + 1));
    itk::EncapsulateMetaData<std::string>(d, "0020|0032", ipp);
    itk::EncapsulateMetaData<std::string>(d, "0020|0037", iop.str());
    itk::EncapsulateMetaData<std::string>(d, "0018|0050", num(image->GetSpacing()[2]));
    itk::EncapsulateMetaData<std::string>(d, "0028|1052", num(rescaleInterceptHU));
    itk::EncapsulateMetaData<std::string>(d, "0028|1053", "1");
    itk::EncapsulateMetaData<std::string>(d, "0028|0004", "MONOCHROME2"); // grey levels, bright = dense
    char name[32];
    std::snprintf(name, sizeof name, "slice%04u.dcm", z);
    files[z] = (staged.path() / name).string();
  }

  // GDCM asserts (SIGABRT) when a write fails part way, e.g. on a full filesystem or past the file size limit,
  // before ITK can turn it into an exception: check the room first (the slices' pixels plus 4 kB of header
  // each, with 10 % to spare), so the common case is one line instead of a signal.
  {
    const std::uintmax_t sliceBytes = std::uintmax_t(size[0]) * size[1] * 2 + 4096;
    const std::uintmax_t needed = sliceBytes * size[2] + sliceBytes * size[2] / 10;
    if (const std::optional<std::uintmax_t> available = freeSpaceQuery()(staged.path().string())) {
      // Three significant digits: a small series needs well under 1 MB, which whole MB would call 0.
      auto megabytes = [](std::uintmax_t bytes) {
        std::ostringstream s;
        s << std::setprecision(3) << double(bytes) / 1048576.0;
        return s.str();
      };
      if (*available < needed)
        throw OutputError(directory + ": not enough room for the DICOM series (" + megabytes(needed) +
                          " MB needed, " + megabytes(*available) + " MB free); free some space or write elsewhere");
    }
    struct rlimit limit {};
    if (getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY && limit.rlim_cur < sliceBytes)
      throw OutputError(directory + ": a DICOM slice (" + std::to_string(sliceBytes) +
                        " bytes) is over the file size limit (ulimit -f); raise it");
  }

  auto io = itk::GDCMImageIO::New();
  io->KeepOriginalUIDOn();
  auto writer = itk::ImageSeriesWriter<ShortImage, SliceImage>::New();
  writer->SetInput(hu);
  writer->SetImageIO(io);
  writer->SetFileNames(files);
  std::vector<itk::MetaDataDictionary*> dictionaryPointers;
  for (auto& d : dictionaries) dictionaryPointers.push_back(&d);
  writer->SetMetaDataDictionaryArray(&dictionaryPointers);
  try {
    writer->Update();
  } catch (const itk::ExceptionObject& e) {
    if (libraryMessagesVerbose()) std::cerr << oneLine(e.GetDescription()) << "\n"; // ITK's words: --verbose only
    throw OutputError(directory + ": cannot write the DICOM series (disk full, file size limit or no permission?); "
                                  "nothing was written");
  }
  // A slice that came out empty or short lost its data without a word (a full disk): not a series.
  for (const std::string& file : files) {
    std::error_code ec;
    if (fs::file_size(file, ec) < std::uintmax_t(size[0]) * size[1] * 2 || ec)
      throw OutputError(directory + ": a DICOM slice came out short (disk full?); nothing was written");
  }
  try {
    staged.publish({"slice####.dcm"});
  } catch (const std::exception&) {
    throw OutputError(directory + ": cannot move the DICOM series into place (a folder in the way, or no "
                                  "permission?)");
  }
}

} // namespace cementsph::imaging
