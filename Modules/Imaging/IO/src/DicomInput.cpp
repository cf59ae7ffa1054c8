#include "cementsph/imaging/DicomInput.h"

#include <gdcmFileMetaInformation.h>
#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmReader.h>
#include <gdcmStringFilter.h>

#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <iostream>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>

namespace cementsph::imaging {

namespace fs = std::filesystem;

namespace {

const gdcm::Tag kPixelData(0x7fe0, 0x0010);

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  std::size_t start = 0;
  while (start < s.size() && s[start] == ' ') ++start;
  return s.substr(start);
}

// Numbers of a DICOM multi-value ("a\b\c"); nullopt unless there are exactly N finite ones.
template <std::size_t N> std::optional<std::array<double, N>> numbers(const std::string& text) {
  std::array<double, N> out{};
  std::size_t count = 0;
  std::stringstream parts(text);
  std::string part;
  while (std::getline(parts, part, '\\')) {
    part = trimmed(part);
    char* end = nullptr;
    const double x = std::strtod(part.c_str(), &end);
    if (part.empty() || end != part.c_str() + part.size() || !std::isfinite(x) || count >= N) return std::nullopt;
    out[count++] = x;
  }
  if (count != N) return std::nullopt;
  return out;
}

int integer(const std::string& text, int fallback) {
  const std::string t = trimmed(text);
  if (t.empty()) return fallback;
  char* end = nullptr;
  const long v = std::strtol(t.c_str(), &end, 10);
  if (end != t.c_str() + t.size() || v < 0 || v > 1 << 30) return -1;
  return static_cast<int>(v);
}

std::string name(const std::string& path) { return fs::path(path).filename().string(); }

std::string mm(double x) {
  std::ostringstream s;
  s.precision(4);
  s << x << " mm";
  return s.str();
}

// GDCM asserts (SIGABRT) on some damaged files, inside gdcm::Reader itself (a DICOMDIR without offsets:
// FileMetaInformation::ReadCompat, "is.good()"), and may on pixel data it cannot decode. An abort cannot be
// caught in-process, so a child process (fork) first runs the same GDCM calls over every file: reading the
// whole file and, with decode, decoding its image as ITK will. The parent learns from a pipe which file the
// child was on; a child killed by a signal, or silent for kProbeSecondsPerFile, names that file. Returns the
// file GDCM failed on, or empty when all went through.
constexpr int kProbeSecondsPerFile = 60;

std::string firstFileGdcmCrashesOn(const std::vector<std::string>& files, bool decode) {
  if (files.empty()) return {};
  int fds[2];
  if (::pipe(fds) != 0) return {}; // no probe possible: read in-process as before
  std::cout.flush();
  std::cerr.flush();
  const pid_t child = ::fork();
  if (child < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    return {};
  }
  if (child == 0) {
    ::close(fds[0]);
    const int devNull = ::open("/dev/null", O_WRONLY);
    if (devNull >= 0) ::dup2(devNull, 2); // GDCM's assertion text would be a second line
    for (std::uint32_t k = 0; k < files.size(); ++k) {
      if (::write(fds[1], &k, sizeof k) != sizeof k) ::_exit(0);
      try {
        if (decode) {
          gdcm::ImageReader reader;
          reader.SetFileName(files[k].c_str());
          if (reader.Read()) {
            const gdcm::Image& image = reader.GetImage();
            std::vector<char> buffer(image.GetBufferLength());
            image.GetBuffer(buffer.data());
          }
        } else {
          gdcm::Reader reader;
          reader.SetFileName(files[k].c_str());
          (void)reader.Read();
        }
      } catch (...) {
        // An exception is handled in the parent as it is now; only crashes matter here.
      }
    }
    const std::uint32_t done = 0xffffffffu;
    (void)!::write(fds[1], &done, sizeof done);
    ::_exit(0);
  }
  ::close(fds[1]);
  std::uint32_t current = 0, value = 0;
  bool finished = false, stalled = false;
  for (;;) {
    pollfd p{fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, kProbeSecondsPerFile * 1000);
    if (ready == 0) {
      stalled = true;
      ::kill(child, SIGKILL);
      break;
    }
    if (ready < 0 && errno == EINTR) continue;
    const ssize_t n = ready > 0 ? ::read(fds[0], &value, sizeof value) : 0;
    if (n != sizeof value) break;
    if (value == 0xffffffffu) finished = true;
    else current = value;
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (stalled || !finished || !WIFEXITED(status)) return files[std::min<std::size_t>(current, files.size() - 1)];
  return {};
}

} // namespace

bool DicomHeader::isDicomDir() const {
  return mediaStorageSopClass == "1.2.840.10008.1.3.10" || sopClass == "1.2.840.10008.1.3.10";
}

std::optional<DicomHeader> readDicomHeader(const std::string& path) {
  DicomHeader h;
  h.path = path;
  try {
    gdcm::Reader reader;
    reader.SetFileName(path.c_str());
    // The whole file (the pixel data element is read, not decoded): ReadUpToTag leaves out the tag itself,
    // and whether pixel data is present is one of the checks.
    if (!reader.Read()) return std::nullopt;
    const gdcm::File& file = reader.GetFile();
    const gdcm::DataSet& ds = file.GetDataSet();
    const gdcm::FileMetaInformation& meta = file.GetHeader();
    if (meta.FindDataElement(gdcm::Tag(0x0002, 0x0002))) {
      const gdcm::ByteValue* bv = meta.GetDataElement(gdcm::Tag(0x0002, 0x0002)).GetByteValue();
      if (bv) h.mediaStorageSopClass = trimmed(std::string(bv->GetPointer(), bv->GetLength()));
    }
    if (ds.IsEmpty() && h.mediaStorageSopClass.empty()) return std::nullopt;
    gdcm::StringFilter strings;
    strings.SetFile(file);
    auto value = [&](std::uint16_t group, std::uint16_t element) -> std::string {
      const gdcm::Tag tag(group, element);
      if (!ds.FindDataElement(tag) || ds.GetDataElement(tag).IsEmpty()) return {};
      return trimmed(strings.ToString(tag));
    };
    h.sopClass = value(0x0008, 0x0016);
    h.modality = value(0x0008, 0x0060);
    h.seriesUid = value(0x0020, 0x000e);
    h.photometric = value(0x0028, 0x0004);
    h.samplesPerPixel = integer(value(0x0028, 0x0002), 1);
    h.frames = integer(value(0x0028, 0x0008), 1);
    h.rows = integer(value(0x0028, 0x0010), 0);
    h.columns = integer(value(0x0028, 0x0011), 0);
    h.bitsAllocated = integer(value(0x0028, 0x0100), 0);
    h.bitsStored = integer(value(0x0028, 0x0101), 0);
    h.highBit = integer(value(0x0028, 0x0102), -1);
    h.position = numbers<3>(value(0x0020, 0x0032));
    h.orientation = numbers<6>(value(0x0020, 0x0037));
    h.pixelSpacing = numbers<2>(value(0x0028, 0x0030));
    h.rescaleSlope = value(0x0028, 0x1053);
    h.rescaleIntercept = value(0x0028, 0x1052);
    h.hasPixelData = ds.FindDataElement(kPixelData);
    if (h.hasPixelData && !meta.GetDataSetTransferSyntax().IsEncapsulated() && h.rows > 0 && h.columns > 0 &&
        h.bitsAllocated > 0) {
      // Uncompressed: the file must be long enough to hold the pixels (a truncated slice is refused here,
      // before any reader trusts its length).
      const std::uintmax_t pixelBytes = std::uintmax_t(h.rows) * std::uintmax_t(h.columns) *
                                        std::uintmax_t(std::max(1, h.samplesPerPixel)) *
                                        std::uintmax_t((h.bitsAllocated + 7) / 8) * std::uintmax_t(std::max(1, h.frames));
      std::error_code ec;
      if (fs::file_size(path, ec) < pixelBytes) h.hasPixelData = false;
      // The Pixel Data element itself must hold them: a short element inside a longer file (other elements
      // around it) would be read shifted or padded with whatever follows.
      const gdcm::ByteValue* pixels = ds.GetDataElement(kPixelData).GetByteValue();
      h.pixelDataBytes = pixels ? std::uintmax_t(pixels->GetLength()) : 0;
      h.pixelDataBytesNeeded = pixelBytes;
      if (h.pixelDataBytes < pixelBytes) h.hasPixelData = false;
    }
  } catch (const std::exception&) {
    return std::nullopt;
  }
  return h;
}

std::string ctSliceProblem(const DicomHeader& h) {
  if (h.isDicomDir()) return "a DICOMDIR index, not an image (give the folder that holds one series' slice files)";
  if (h.modality != "CT")
    return "modality is " + (h.modality.empty() ? std::string("missing") : "'" + h.modality + "'") +
           ", not CT: only CT values are Hounsfield units";
  // MONOCHROME1 only says how to display the grey (bright = low); a CT's HU are Rescale Slope x stored value +
  // Rescale Intercept either way. ITK's DICOM reader inverts MONOCHROME1 stored values before rescaling, which
  // turns bone into air: refused rather than read wrong.
  if (h.samplesPerPixel == 1 && h.photometric == "MONOCHROME1")
    return "photometric interpretation MONOCHROME1 (inverted grey), which this program's DICOM reader would "
           "invert into wrong HU; export the series as MONOCHROME2";
  if (h.samplesPerPixel != 1 || (h.photometric != "MONOCHROME1" && h.photometric != "MONOCHROME2"))
    return "a colour image (photometric interpretation '" + h.photometric + "', " + std::to_string(h.samplesPerPixel) +
           " samples per pixel); a CT is one grey value per pixel";
  if (h.frames != 1)
    return "a multi-frame file (" + std::to_string(h.frames) +
           " frames), not supported: export the CT as one file per slice";
  if (h.hasPixelData == false && h.pixelDataBytesNeeded > 0 && h.pixelDataBytes < h.pixelDataBytesNeeded)
    return "its pixel data holds " + std::to_string(h.pixelDataBytes) + " bytes where " + std::to_string(h.rows) + " rows x " +
           std::to_string(h.columns) + " columns need " + std::to_string(h.pixelDataBytesNeeded) +
           " (truncated or damaged slice); export the series again";
  if (!h.hasPixelData) return "no pixel data, or fewer bytes than its rows and columns need (truncated?)";
  // Bits Stored and High Bit say which bits of each Bits Allocated word hold the value: more stored bits than
  // allocated, or a high bit outside the word or below the stored bits, is no layout (GDCM read such slices
  // with some layout of its own choosing, silently).
  if (h.bitsAllocated > 0 && (h.bitsStored > h.bitsAllocated || (h.highBit >= 0 && (h.highBit >= h.bitsAllocated ||
                                                                                    h.highBit + 1 < h.bitsStored))))
    return "Bits Stored " + std::to_string(h.bitsStored) + " / High Bit " + std::to_string(h.highBit) +
           " do not fit its Bits Allocated " + std::to_string(h.bitsAllocated) +
           " (damaged header), so its values are unknown; export the series again";
  // HU = Rescale Slope x stored value + Rescale Intercept: a slope that is not a number, or zero (every
  // voxel the intercept), or an intercept that is not a number makes every HU of the slice wrong.
  if (!h.rescaleSlope.empty() || !h.rescaleIntercept.empty()) {
    const auto slope = numbers<1>(h.rescaleSlope.empty() ? "1" : h.rescaleSlope);
    const auto intercept = numbers<1>(h.rescaleIntercept.empty() ? "0" : h.rescaleIntercept);
    if (!slope || (*slope)[0] == 0 || !intercept) {
      std::string shown = "Rescale Slope '" + h.rescaleSlope.substr(0, 20) + "', Rescale Intercept '" +
                          h.rescaleIntercept.substr(0, 20) + "'";
      for (char& c : shown)
        if (static_cast<unsigned char>(c) < 32) c = '?';
      return shown + ": not finite numbers with a non-zero slope, so its HU are unknown (damaged header?)";
    }
  }
  if (h.rows < 2 || h.columns < 2) return "has no usable image size (rows " + std::to_string(h.rows) + ", columns " +
                                          std::to_string(h.columns) + ")";
  if (!h.position || !h.orientation || !h.pixelSpacing)
    return "lacks Image Position (Patient), Image Orientation (Patient) or Pixel Spacing: its geometry is unknown";
  const auto& o = *h.orientation;
  const double rowNorm = std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
  const double colNorm = std::sqrt(o[3] * o[3] + o[4] * o[4] + o[5] * o[5]);
  const double dot = o[0] * o[3] + o[1] * o[4] + o[2] * o[5];
  if (std::abs(rowNorm - 1) > 1e-3 || std::abs(colNorm - 1) > 1e-3 || std::abs(dot) > 1e-3)
    return "Image Orientation (Patient) is not two orthogonal unit vectors";
  for (double s : *h.pixelSpacing)
    if (!(s >= 1e-3 && s <= 100)) return "pixel spacing " + mm(s) + " is outside 0.001..100 mm";
  return {};
}

std::vector<std::string> ctSeriesFiles(const std::string& directory) {
  std::vector<DicomHeader> headers;
  bool sawDicomDir = false;
  std::error_code ec;
  std::vector<fs::path> paths;
  for (fs::directory_iterator it(directory, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec)) paths.push_back(it->path());
  if (ec) throw std::runtime_error(directory + ": cannot list the folder: " + ec.message());
  std::sort(paths.begin(), paths.end());
  {
    std::vector<std::string> names;
    for (const fs::path& p : paths) names.push_back(p.string());
    const std::string crash = firstFileGdcmCrashesOn(names, false);
    if (!crash.empty())
      throw std::runtime_error(directory + ": " + name(crash) +
                               ": GDCM cannot parse this file (damaged DICOM?); remove it from the folder");
  }
  for (const fs::path& p : paths) {
    auto h = readDicomHeader(p.string());
    if (!h) continue;
    if (h->isDicomDir()) {
      sawDicomDir = true;
      continue;
    }
    headers.push_back(std::move(*h));
  }
  if (headers.empty())
    throw std::runtime_error(directory + (sawDicomDir ? ": holds a DICOMDIR index but no slice files; give the folder "
                                                        "that holds one series' slices"
                                                      : ": folder holds no DICOM series"));
  std::map<std::string, std::vector<const DicomHeader*>> bySeries;
  for (const DicomHeader& h : headers) bySeries[h.seriesUid].push_back(&h);
  std::vector<const DicomHeader*>* volume = nullptr;
  std::size_t volumes = 0;
  for (auto& [uid, slices] : bySeries)
    if (slices.size() >= 2) {
      ++volumes;
      volume = &slices;
    }
  if (volumes > 1)
    throw std::runtime_error(directory + ": folder holds " + std::to_string(volumes) +
                             " series of several slices (different Series Instance UIDs); put one series per folder");
  if (!volume) {
    const DicomHeader& only = *bySeries.begin()->second.front();
    const std::string problem = ctSliceProblem(only);
    if (!problem.empty()) throw std::runtime_error(directory + ": " + name(only.path) + ": " + problem);
    throw std::runtime_error(directory + ": DICOM series has 1 slice(s); a 3-D volume needs at least 2");
  }
  std::vector<const DicomHeader*>& slices = *volume;
  for (const DicomHeader* h : slices) {
    const std::string problem = ctSliceProblem(*h);
    if (!problem.empty()) throw std::runtime_error(directory + ": " + name(h->path) + ": " + problem);
  }
  const DicomHeader& first = *slices.front();
  const auto& o = *first.orientation;
  const std::array<double, 3> normal{o[1] * o[5] - o[2] * o[4], o[2] * o[3] - o[0] * o[5], o[0] * o[4] - o[1] * o[3]};
  for (const DicomHeader* h : slices) {
    bool same = h->rows == first.rows && h->columns == first.columns;
    for (int i = 0; i < 6 && same; ++i) same = std::abs((*h->orientation)[i] - o[i]) < 1e-4;
    for (int i = 0; i < 2 && same; ++i)
      same = std::abs((*h->pixelSpacing)[i] - (*first.pixelSpacing)[i]) < 1e-4 * (*first.pixelSpacing)[i];
    if (!same)
      throw std::runtime_error(directory + ": " + name(h->path) + " differs from " + name(first.path) +
                               " in size, pixel spacing or orientation: not one volume");
  }
  auto along = [&](const DicomHeader* h) {
    const auto& p = *h->position;
    return p[0] * normal[0] + p[1] * normal[1] + p[2] * normal[2];
  };
  std::stable_sort(slices.begin(), slices.end(),
                   [&](const DicomHeader* a, const DicomHeader* b) { return along(a) < along(b); });
  std::vector<double> gaps;
  for (std::size_t k = 1; k < slices.size(); ++k) gaps.push_back(along(slices[k]) - along(slices[k - 1]));
  std::vector<double> sortedGaps = gaps;
  std::nth_element(sortedGaps.begin(), sortedGaps.begin() + long(sortedGaps.size() / 2), sortedGaps.end());
  const double typical = sortedGaps[sortedGaps.size() / 2];
  for (std::size_t k = 0; k < gaps.size(); ++k) {
    const std::string pair = name(slices[k]->path) + " and " + name(slices[k + 1]->path);
    if (gaps[k] < 1e-3)
      throw std::runtime_error(directory + ": " + pair + " lie at the same position (a duplicated slice); remove one");
    // DICOM stores positions as decimal text: 1 % of the spacing covers its rounding, not a missing slice.
    if (std::abs(gaps[k] - typical) > 0.01 * typical + 1e-3)
      throw std::runtime_error(directory + ": uneven slice spacing: " + mm(gaps[k]) + " between " + pair +
                               " where the others are " + mm(typical) + " (a missing or misplaced slice?)");
  }
  if (!(typical >= 1e-3 && typical <= 100))
    throw std::runtime_error(directory + ": slice spacing " + mm(typical) + " is outside 0.001..100 mm");
  // Positions off the normal through the first slice: a sheared stack (gantry tilt), which a volume with one
  // direction matrix cannot represent.
  const auto& p0 = *first.position;
  for (const DicomHeader* h : slices) {
    const auto& p = *h->position;
    const double s = along(h) - along(&first);
    double offPlane = 0;
    for (int i = 0; i < 3; ++i) offPlane += std::pow(p[i] - p0[i] - s * normal[i], 2);
    if (std::sqrt(offPlane) > 0.01 * typical + 1e-2)
      throw std::runtime_error(directory + ": " + name(h->path) +
                               " is shifted across the slice normal (gantry tilt?); such a stack is not supported");
  }
  std::vector<std::string> files;
  for (const DicomHeader* h : slices) files.push_back(h->path);
  const std::string crash = firstFileGdcmCrashesOn(files, true);
  if (!crash.empty())
    throw std::runtime_error(directory + ": " + name(crash) + ": GDCM cannot decode its pixel data (damaged slice?)");
  return files;
}

void refuseSingleDicomFile(const std::string& path) {
  if (!firstFileGdcmCrashesOn({path}, false).empty())
    throw std::runtime_error(path + ": GDCM cannot parse this file (damaged DICOM, or a DICOMDIR it does not "
                                    "understand)");
  const auto h = readDicomHeader(path);
  if (!h) throw std::runtime_error(path + ": not a readable DICOM file (corrupt or truncated?)");
  const std::string problem = ctSliceProblem(*h);
  if (!problem.empty()) throw std::runtime_error(path + ": " + problem);
  throw std::runtime_error(path + ": a single CT slice; give the folder that holds the whole series");
}

} // namespace cementsph::imaging
