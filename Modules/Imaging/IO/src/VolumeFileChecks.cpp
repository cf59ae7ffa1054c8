#include "VolumeFileChecks.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <stdexcept>
#include <vector>

namespace cementsph::imaging::detail {

namespace fs = std::filesystem;

namespace {

constexpr std::uintmax_t kNiftiHeaderBytes = 348;
constexpr std::size_t kLongestHeader = 1 << 20; // text headers longer than 1 MiB are not headers

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

// A text header read line by line: keys (lower case) -> values, and the byte offset just after the header.
struct TextHeader {
  std::map<std::string, std::string> fields;
  std::uintmax_t dataOffset = 0;
  bool complete = false; // the terminating line (blank line for NRRD, ElementDataFile for MetaImage) was seen
};

TextHeader readTextHeader(const std::string& path, char separator, const std::string& lastKey) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  TextHeader h;
  std::string line;
  std::uintmax_t offset = 0;
  bool firstLine = true;
  while (offset < kLongestHeader && std::getline(in, line)) {
    offset += line.size() + 1;
    if (separator == ':' && firstLine) { // NRRD magic "NRRD000X"
      firstLine = false;
      continue;
    }
    firstLine = false;
    const std::string t = trim(line);
    if (t.empty()) {
      if (lastKey.empty()) { // NRRD: a blank line ends the header
        h.complete = true;
        break;
      }
      continue;
    }
    if (t[0] == '#') continue;
    auto at = t.find(separator == ':' ? ":=" : "=");
    std::size_t width = 2;
    if (separator == ':' && at == std::string::npos) {
      at = t.find(':');
      width = 1;
    } else if (separator != ':') {
      width = 1;
    }
    if (at == std::string::npos) continue;
    const std::string key = lower(trim(t.substr(0, at)));
    h.fields[key] = trim(t.substr(at + width));
    if (!lastKey.empty() && key == lastKey) {
      h.complete = true;
      break;
    }
  }
  h.dataOffset = offset;
  return h;
}

// Inflates a zlib (MetaImage) or gzip (NRRD, NIfTI) stream from offset to its end, verifying its checksum;
// returns the decompressed size. Throws for a corrupt or cut-short stream.
std::uintmax_t inflatedBytes(const std::string& path, std::uintmax_t offset, bool gzip) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open the data file");
  in.seekg(static_cast<std::streamoff>(offset));
  z_stream z{};
  if (inflateInit2(&z, gzip ? 16 + MAX_WBITS : MAX_WBITS) != Z_OK) throw std::runtime_error(path + ": zlib failed");
  std::vector<unsigned char> input(1 << 16), output(1 << 18);
  std::uintmax_t total = 0;
  int code = Z_OK;
  while (code != Z_STREAM_END) {
    if (z.avail_in == 0) {
      in.read(reinterpret_cast<char*>(input.data()), static_cast<std::streamsize>(input.size()));
      const auto got = in.gcount();
      if (got <= 0) break;
      z.next_in = input.data();
      z.avail_in = static_cast<unsigned>(got);
    }
    z.next_out = output.data();
    z.avail_out = static_cast<unsigned>(output.size());
    code = inflate(&z, Z_NO_FLUSH);
    total += output.size() - z.avail_out;
    if (code != Z_OK && code != Z_STREAM_END && code != Z_BUF_ERROR) break;
  }
  const std::string message = z.msg ? z.msg : "";
  inflateEnd(&z);
  if (code == Z_STREAM_END) return total;
  if (code == Z_DATA_ERROR || code == Z_NEED_DICT || code == Z_MEM_ERROR)
    throw std::runtime_error(path + ": corrupt compressed data (" + (message.empty() ? "zlib error" : message) + ")");
  throw std::runtime_error(path + ": compressed data ends early (truncated file?)");
}

void requireBytes(const std::string& path, std::uintmax_t available, std::uintmax_t needed) {
  if (available < needed)
    throw std::runtime_error(path + ": truncated (" + std::to_string(available) + " bytes of image data, " +
                             std::to_string(needed) + " expected)");
}

std::uintmax_t fileSize(const std::string& path) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec) throw std::runtime_error(path + ": cannot open the data file: " + ec.message());
  return size;
}

std::string besideHeader(const std::string& header, const std::string& dataFile) {
  const fs::path p(dataFile);
  return p.is_absolute() ? dataFile : (fs::path(header).parent_path() / p).string();
}

void checkNrrdPayload(const std::string& path, std::uintmax_t imageBytes) {
  const TextHeader h = readTextHeader(path, ':', "");
  const std::string encoding = lower(h.fields.count("encoding") ? h.fields.at("encoding") : "raw");
  std::string dataFile = h.fields.count("data file") ? h.fields.at("data file")
                         : h.fields.count("datafile") ? h.fields.at("datafile") : "";
  // Skips, lists of data files and formatted file names: left to ITK.
  for (const char* key : {"line skip", "lineskip", "byte skip", "byteskip"})
    if (h.fields.count(key) && trim(h.fields.at(key)) != "0") return;
  if (dataFile.find(' ') != std::string::npos || lower(dataFile).rfind("list", 0) == 0) return;
  if (dataFile.empty() && !h.complete) throw std::runtime_error(path + ": NRRD header has no end (no blank line)");
  const std::string data = dataFile.empty() ? path : besideHeader(path, dataFile);
  const std::uintmax_t offset = dataFile.empty() ? h.dataOffset : 0;
  if (encoding == "gzip" || encoding == "gz")
    requireBytes(path, inflatedBytes(data, offset, true), imageBytes);
  else if (encoding == "raw") {
    const auto size = fileSize(data);
    requireBytes(path, size > offset ? size - offset : 0, imageBytes);
  }
}

void checkMetaPayload(const std::string& path, std::uintmax_t imageBytes) {
  const TextHeader h = readTextHeader(path, '=', "elementdatafile");
  const std::string dataFile = h.fields.at("elementdatafile");
  const std::string kind = lower(dataFile);
  if (kind == "list" || dataFile.find(' ') != std::string::npos || dataFile.find('%') != std::string::npos) return;
  const bool local = kind == "local";
  const std::string data = local ? path : besideHeader(path, dataFile);
  const std::uintmax_t offset = local ? h.dataOffset : 0;
  const bool compressed = h.fields.count("compresseddata") && lower(h.fields.at("compresseddata")) == "true";
  if (compressed) {
    requireBytes(path, inflatedBytes(data, offset, false), imageBytes);
  } else {
    const auto size = fileSize(data);
    requireBytes(path, size > offset ? size - offset : 0, imageBytes);
  }
}

void checkNiftiPayload(const std::string& path, std::uintmax_t imageBytes) {
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[2] = {0, 0};
  in.read(reinterpret_cast<char*>(magic), 2);
  const bool gzip = magic[0] == 0x1f && magic[1] == 0x8b;
  const std::uintmax_t available = gzip ? inflatedBytes(path, 0, true) : fileSize(path);
  // A .hdr/.img pair keeps its pixels in the .img file: left to ITK.
  if (lower(fs::path(path).extension().string()) == ".hdr") return;
  requireBytes(path, available, imageBytes + kNiftiHeaderBytes);
}

// NIfTI-1 before ITK reads it (header fields in the header's byte order, which sizeof_hdr = 348 at byte 0
// gives):
//  * the scaling to the stored values' units (scl_slope at byte 112, scl_inter at 116): a NaN or infinite
//    factor makes every HU unknown (nifti_io would skip a NaN slope and hand the raw values on as HU);
//  * floating-point voxels (datatype 16 or 64, at byte 70; the data at vox_offset, byte 108): nifti_io sets
//    NaN and infinite voxels to 0 as it reads them, silently, so they are looked for here first.
void checkNifti(const std::string& path) {
  if (lower(fs::path(path).extension().string()) == ".hdr") return; // the pair's header: left to ITK
  gzFile in = gzopen(path.c_str(), "rb"); // reads plain files too
  if (!in) return;
  unsigned char header[kNiftiHeaderBytes];
  const int got = gzread(in, header, unsigned(kNiftiHeaderBytes));
  if (got != int(kNiftiHeaderBytes)) {
    gzclose(in);
    return; // a short header is the payload check's to report
  }
  std::uint32_t size = 0;
  std::memcpy(&size, header, 4);
  const bool swapped = size != kNiftiHeaderBytes;
  auto field = [&](std::size_t at, std::size_t bytes, void* out) {
    unsigned char b[8];
    std::memcpy(b, header + at, bytes);
    if (swapped) std::reverse(b, b + bytes);
    std::memcpy(out, b, bytes);
  };
  float slope = 0, intercept = 0, voxOffset = 0;
  std::int16_t datatype = 0, dims[8] = {};
  field(112, 4, &slope);
  field(116, 4, &intercept);
  field(108, 4, &voxOffset);
  field(70, 2, &datatype);
  for (int i = 0; i < 8; ++i) field(40 + 2 * std::size_t(i), 2, &dims[i]);
  if (!std::isfinite(slope) || !std::isfinite(intercept)) {
    gzclose(in);
    throw std::runtime_error(path + ": NIfTI scaling scl_slope " + std::to_string(slope) + ", scl_inter " +
                             std::to_string(intercept) + " is not finite, so no voxel's HU is known (damaged header?)");
  }
  const std::size_t bytes = datatype == 16 ? 4 : datatype == 64 ? 8 : 0;
  if (bytes == 0 || !(voxOffset >= float(kNiftiHeaderBytes)) || dims[0] < 3) {
    gzclose(in);
    return;
  }
  std::uintmax_t voxels = 1;
  for (int i = 1; i <= std::min<int>(dims[0], 7); ++i) voxels *= std::uintmax_t(std::max<std::int16_t>(dims[i], 1));
  gzseek(in, z_off_t(voxOffset), SEEK_SET);
  std::vector<unsigned char> chunk(bytes * 65536);
  std::uintmax_t index = 0;
  while (index < voxels) {
    const std::size_t want = std::size_t(std::min<std::uintmax_t>(65536, voxels - index));
    const int read = gzread(in, chunk.data(), unsigned(want * bytes));
    if (read <= 0) break; // short data: the payload check reports it
    const std::size_t n = std::size_t(read) / bytes;
    for (std::size_t k = 0; k < n; ++k, ++index) {
      unsigned char* v = chunk.data() + k * bytes;
      if (swapped) std::reverse(v, v + bytes);
      double x;
      if (bytes == 4) {
        float f;
        std::memcpy(&f, v, 4);
        x = f;
      } else {
        std::memcpy(&x, v, 8);
      }
      if (!std::isfinite(x)) {
        gzclose(in);
        const std::uintmax_t nx = std::uintmax_t(std::max<std::int16_t>(dims[1], 1)),
                             ny = std::uintmax_t(std::max<std::int16_t>(dims[2], 1));
        throw std::runtime_error(path + ": voxel (" + std::to_string(index % nx) + "," + std::to_string(index / nx % ny) +
                                 "," + std::to_string(index / (nx * ny)) + ") is " + (std::isnan(x) ? "NaN" : "infinite") +
                                 "; a CT must hold finite values");
      }
    }
  }
  gzclose(in);
}

} // namespace

void checkHeaderBeforeItk(const std::string& path, VolumeFormat format) {
  if (format == VolumeFormat::Nifti) checkNifti(path);
  if (format != VolumeFormat::MetaImage) return;
  const TextHeader h = readTextHeader(path, '=', "elementdatafile");
  if (!h.complete)
    throw std::runtime_error(path + ": MetaImage header has no ElementDataFile key (misspelled?), so where its "
                                    "voxels are is unknown; the last header key must be ElementDataFile = LOCAL "
                                    "or a file name");
}

void checkPayload(const std::string& path, VolumeFormat format, std::uintmax_t imageBytes) {
  switch (format) {
  case VolumeFormat::Nrrd: checkNrrdPayload(path, imageBytes); break;
  case VolumeFormat::MetaImage: checkMetaPayload(path, imageBytes); break;
  case VolumeFormat::Nifti: checkNiftiPayload(path, imageBytes); break;
  }
}

} // namespace cementsph::imaging::detail
