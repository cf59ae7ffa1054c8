#include "VolumeFileChecks.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <cctype>
#include <cerrno>
#include <array>
#include <initializer_list>
#include <sstream>
#include <filesystem>
#include <fstream>
#include <iterator>
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
  std::vector<std::string> order; // the keys as the header gives them, first to last
  std::uintmax_t dataOffset = 0;
  bool complete = false; // the terminating line (blank line for NRRD, ElementDataFile for MetaImage) was seen
  bool tooLong = false;  // reading stopped at kLongestHeader
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
    // A header is text: a control byte (a NUL above all) in a field would be cut off or carried into file
    // names and messages (nrrd_header fuzz finding: "data file: data.raw\0\0.gzz"). A NRRD header is text up
    // to its blank line, so such a line is refused. In a MetaImage whose ElementDataFile line is missing or
    // misspelt, reading runs on into LOCAL binary data: a control byte there ends the header (the checks
    // that follow name the missing key), unless it sits in the ElementDataFile line itself.
    const bool controlByte = std::any_of(t.begin(), t.end(), [](char c) {
      return (static_cast<unsigned char>(c) < 0x20 && c != '\t') || c == 0x7f;
    });
    if (controlByte) {
      if (separator != ':' && lower(trim(t.substr(0, at))) != lastKey) break;
      throw std::runtime_error(path + ": header line " + shownValue(t.substr(0, std::min<std::size_t>(at, 40))) +
                               " holds a control byte; a header is text: fix or re-export the file");
    }
    const std::string key = lower(trim(t.substr(0, at)));
    h.fields[key] = trim(t.substr(at + width));
    h.order.push_back(key);
    if (!lastKey.empty() && key == lastKey) {
      h.complete = true;
      break;
    }
  }
  h.dataOffset = offset;
  h.tooLong = !h.complete && offset >= kLongestHeader;
  return h;
}

// Inflates a zlib (MetaImage) or gzip (NRRD, NIfTI) stream from offset to its end, verifying its checksum;
// returns the decompressed size. Throws for a corrupt or cut-short stream. A gzip file may hold several
// members one after another (gzip's own output when files are concatenated, pigz, some writers): zlib's
// gzread, which the readers use, reads them all, so each further member is inflated too (inflateReset at
// Z_STREAM_END while a gzip magic follows); bytes after the last member that are not a member are ignored
// as gzread ignores them.
std::uintmax_t inflatedBytes(const std::string& path, std::uintmax_t offset, bool gzip) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open the data file");
  in.seekg(static_cast<std::streamoff>(offset));
  z_stream z{};
  if (inflateInit2(&z, gzip ? 16 + MAX_WBITS : MAX_WBITS) != Z_OK) throw std::runtime_error(path + ": zlib failed");
  std::vector<unsigned char> input(1 << 16), output(1 << 18);
  auto refill = [&]() -> bool { // more input at z.next_in; keeps what was not consumed yet
    if (z.avail_in > 0 && z.next_in != input.data()) std::memmove(input.data(), z.next_in, z.avail_in);
    in.read(reinterpret_cast<char*>(input.data()) + z.avail_in, static_cast<std::streamsize>(input.size() - z.avail_in));
    const auto got = in.gcount();
    z.next_in = input.data();
    z.avail_in += static_cast<unsigned>(std::max<std::streamsize>(got, 0));
    return got > 0;
  };
  std::uintmax_t total = 0;
  int code = Z_OK;
  for (;;) {
    if (z.avail_in == 0 && !refill()) break;
    z.next_out = output.data();
    z.avail_out = static_cast<unsigned>(output.size());
    code = inflate(&z, Z_NO_FLUSH);
    total += output.size() - z.avail_out;
    if (code == Z_STREAM_END) {
      if (!gzip) break;
      if (z.avail_in < 2) refill();
      if (z.avail_in < 2 || z.next_in[0] != 0x1f || z.next_in[1] != 0x8b) break; // no further member
      if (inflateReset(&z) != Z_OK) break;
      code = Z_OK;
      continue;
    }
    if (code != Z_OK && code != Z_BUF_ERROR) break;
    if (code == Z_BUF_ERROR && z.avail_in > 0 && z.avail_out > 0) break; // no progress possible
  }
  inflateEnd(&z); // zlib's own words (z.msg) stay out of the message: they name no file and no remedy
  if (code == Z_STREAM_END) return total;
  if (code == Z_DATA_ERROR || code == Z_NEED_DICT || code == Z_MEM_ERROR)
    throw std::runtime_error(path + ": corrupt compressed data (a bad checksum or damaged bytes); the file cannot "
                                    "be read, export it again");
  throw std::runtime_error(path + ": compressed data ends early (truncated file?); export it again");
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

// ---- Pieces every header check uses ----

[[noreturn]] void refuse(const std::string& path, const std::string& what) { throw std::runtime_error(path + ": " + what); }

std::vector<std::string> words(const std::string& text) {
  std::vector<std::string> out;
  std::string w;
  for (char c : text) {
    if (std::isspace(static_cast<unsigned char>(c))) {
      if (!w.empty()) out.push_back(w);
      w.clear();
    } else {
      w += c;
    }
  }
  if (!w.empty()) out.push_back(w);
  return out;
}

// The whole token as a number (strtod also takes "nan" and "inf": the callers say what is wrong with them).
std::optional<double> toNumber(const std::string& w) {
  if (w.empty()) return std::nullopt;
  char* end = nullptr;
  const double x = std::strtod(w.c_str(), &end);
  if (end != w.c_str() + w.size()) return std::nullopt;
  return x;
}

// The whole token as an integer that fits an int (both MetaIO and teem keep these in an int).
std::optional<long long> toInteger(const std::string& w) {
  if (w.empty()) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const long long x = std::strtoll(w.c_str(), &end, 10);
  if (errno == ERANGE || end != w.c_str() + w.size() || x < -2147483647LL || x > 2147483647LL) return std::nullopt;
  return x;
}

std::string number(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// Exactly n numbers from a header value, or a line naming the key.
std::vector<double> numbersOf(const std::string& path, const std::string& key, const std::string& value, std::size_t n) {
  const auto w = words(value);
  std::vector<double> out;
  for (const std::string& t : w) {
    const auto x = toNumber(t);
    if (!x) break;
    out.push_back(*x);
  }
  if (w.size() != n || out.size() != n)
    refuse(path, key + " = " + shownValue(value) + " is not " + std::to_string(n) + " numbers (damaged header?)");
  return out;
}

// A header's voxel count within what is read (before a reader allocates, or data is decompressed, for it).
void requireVoxelCount(const std::string& path, const std::string& key, double voxels) {
  if (voxels > kMaxVoxels)
    refuse(path, key + " claims " + number(voxels) + " voxels, more than this program reads (2^30)");
}

// A spacing from the header itself: readers replace a NaN, infinite or zero spacing by 1 mm without a word,
// so the value in the file is checked, not what the reader makes of it.
void requireSpacing(const std::string& path, const std::string& what, double mm) {
  if (!(mm >= kMinSpacingMm && mm <= kMaxSpacingMm))
    refuse(path, what + " " + number(mm) + " mm is not a voxel spacing (a CT's is a finite 0.001..100 mm; "
                                           "damaged header?)");
}

// A data-file name pattern (MetaImage and NRRD: "name%03d.raw min max step"). The pattern becomes a printf
// format in both readers, and it comes from the file: anything but one integer conversion reads or writes
// memory it should not (%s, %n, %99999d) or makes glibc abort. Allowed: text, "%%" and exactly one
// %[0-+ ]d or %[0-+ ]i with a width of at most 2 digits. The number is formatted here without printf.
struct FilePattern {
  std::string before, after;
  bool zeroPad = false, leftAlign = false, plus = false, space = false;
  int width = 0;
  std::string name(long long k) const {
    std::string digits = std::to_string(k < 0 ? -k : k);
    const std::string sign = k < 0 ? "-" : plus ? "+" : space ? " " : "";
    std::string body = sign + digits;
    if (int(body.size()) < width) {
      const std::size_t pad = std::size_t(width) - body.size();
      if (leftAlign) body += std::string(pad, ' ');
      else if (zeroPad) body = sign + std::string(pad, '0') + digits;
      else body = std::string(pad, ' ') + body;
    }
    return before + body + after;
  }
};

std::optional<FilePattern> filePattern(const std::string& format) {
  FilePattern p;
  int conversions = 0;
  std::string* text = &p.before;
  for (std::size_t i = 0; i < format.size(); ++i) {
    if (format[i] != '%') {
      *text += format[i];
      continue;
    }
    if (i + 1 < format.size() && format[i + 1] == '%') {
      *text += '%';
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    for (; j < format.size() && std::strchr("0-+ ", format[j]) && format[j] != '\0'; ++j) {
      p.zeroPad |= format[j] == '0';
      p.leftAlign |= format[j] == '-';
      p.plus |= format[j] == '+';
      p.space |= format[j] == ' ';
    }
    std::size_t digits = 0;
    // At most two width digits are accepted below; stop accumulating past them so a long digit run cannot
    // overflow the width (UBSan finding of the nrrd_header fuzz target).
    for (; j < format.size() && std::isdigit(static_cast<unsigned char>(format[j])); ++j, ++digits)
      if (digits < 2) p.width = p.width * 10 + (format[j] - '0');
    if (digits > 2 || j >= format.size() || (format[j] != 'd' && format[j] != 'i')) return std::nullopt;
    if (++conversions > 1) return std::nullopt;
    text = &p.after;
    i = j;
  }
  if (conversions != 1) return std::nullopt;
  return p;
}

// The files a pattern "format min max step" names, in the order they are read; step 0, a step leading away
// from max, or a count other than `count` is refused (MetaIO divides by the step and loops on it; a count
// above the slices writes past its buffer; one below leaves slices unread).
std::vector<std::string> patternFiles(const std::string& path, const std::string& key, const std::string& value,
                                      const std::vector<std::string>& w, long long count, bool negativeStepAllowed) {
  const std::string what = key + " = " + shownValue(value);
  const auto pattern = filePattern(w[0]);
  if (!pattern)
    refuse(path, what + ": a data-file pattern must hold exactly one integer conversion such as %03d (and "
                        "no other %); fix the header");
  if (w.size() < 4)
    refuse(path, what + ": a data-file pattern needs its numbers written out: 'name%03d.raw first last step'");
  const auto first = toInteger(w[1]), last = toInteger(w[2]), step = toInteger(w[3]);
  if (!first || !last || !step)
    refuse(path, what + ": first, last and step of a data-file pattern must be integers");
  if (*step == 0 || (*step < 0 && !negativeStepAllowed))
    refuse(path, what + ": step " + std::to_string(*step) + " must be a positive integer (the files are numbered "
                        "first, first+step, ..., last)");
  const long long span = *last - *first;
  if ((span != 0 && (span > 0) != (*step > 0)))
    refuse(path, what + ": step " + std::to_string(*step) + " does not lead from " + std::to_string(*first) + " to " +
                     std::to_string(*last));
  const long long files = span / *step + 1;
  // A CT has hundreds of slices; a million files is far past any and keeps the name list (and the time to
  // look for each file) bounded for a header that claims billions.
  if (files > 1000000)
    refuse(path, what + " names " + std::to_string(files) + " data files, more than the 1000000 this program reads");
  if (files != count)
    refuse(path, what + " names " + std::to_string(files) + " data files, but the image needs " +
                     std::to_string(count) + " (one per slice); fix first, last or step");
  std::vector<std::string> names;
  for (long long k = 0; k < files; ++k) names.push_back(pattern->name(*first + k * *step));
  return names;
}

// The non-empty lines after the line that holds `key` (a LIST of data files follows its key).
std::vector<std::string> linesAfterKey(const std::string& path, const std::string& key, char separator,
                                       std::size_t* blankLinesAtEnd = nullptr) {
  std::ifstream in(path, std::ios::binary);
  std::vector<std::string> out;
  std::string line;
  bool listing = false;
  std::uintmax_t read = 0;
  while (std::getline(in, line) && read < (kLongestHeader << 4)) {
    read += line.size() + 1;
    if (listing) {
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
      out.push_back(line);
      continue;
    }
    const auto at = line.find(separator);
    if (at != std::string::npos && lower(trim(line.substr(0, at))) == key) listing = true;
  }
  std::size_t blank = 0;
  while (!out.empty() && out.back().empty()) { // a final newline is no file
    out.pop_back();
    ++blank;
  }
  if (blankLinesAtEnd) *blankLinesAtEnd = blank;
  return out;
}

enum class Packing { Raw, Zlib, Gzip };

// One data file must hold `bytes` after `offset` (decompressed to its end where packed).
void requireDataFile(const std::string& header, const std::string& file, std::uintmax_t offset, Packing packing,
                     std::uintmax_t bytes) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    refuse(header, "data file " + shownValue(fs::path(file).filename().string()) +
                       " is missing; put it beside the header or fix the header's file name");
  const std::uintmax_t available =
      packing == Packing::Raw ? [&] { const auto n = fileSize(file); return n > offset ? n - offset : 0; }()
                              : inflatedBytes(file, offset, packing == Packing::Gzip);
  if (available < bytes)
    refuse(header, "data file " + shownValue(fs::path(file).filename().string()) + " holds " +
                       std::to_string(available) + " bytes of image data, " + std::to_string(bytes) +
                       " expected (truncated?); export the volume again");
}

// ---- MetaImage ----

// The files a MetaImage's voxels are in when there are several (ElementDataFile = LIST, or a pattern),
// beside the header; empty for LOCAL or one file. Throws unless there is exactly one existing file per
// slice: MetaIO reads one name per line after LIST and leaves slices unread when lines run out, and
// reads a pattern's files into slice after slice of its buffer, past its end when there are too many.
// DimSize was checked before (checkMetaHeader).
std::vector<std::string> metaDataFiles(const std::string& path, const TextHeader& h) {
  const std::string dataFile = h.fields.at("elementdatafile");
  const auto w = words(dataFile);
  std::array<long long, 3> size{};
  const auto d = words(h.fields.at("dimsize"));
  for (std::size_t i = 0; i < 3; ++i) size[i] = toInteger(d[i]).value_or(1);
  std::vector<std::string> names;
  if (!w.empty() && w[0] == "LIST") {
    long long fileDim = 2; // "LIST", "LIST 2D": one slice per file
    if (w.size() > 1 && std::isdigit(static_cast<unsigned char>(w[1][0]))) fileDim = w[1][0] - '0';
    if (fileDim < 1 || fileDim > 3) fileDim = 2;
    long long needed = 1;
    for (long long a = fileDim; a < 3; ++a) needed *= size[std::size_t(a)];
    names = linesAfterKey(path, "elementdatafile", '=');
    // Exactly one per slice: with more, which of them hold the volume is a guess (MetaIO read the first ones).
    if (static_cast<long long>(names.size()) != needed)
      refuse(path, "ElementDataFile = LIST names " + std::to_string(names.size()) + " data files, but DimSize needs " +
                       std::to_string(needed) + "; list exactly one file per slice");
    for (std::size_t k = 0; k < names.size(); ++k)
      if (names[k].empty() || names[k].size() > 1000) // MetaIO reads names into a 1024-byte buffer
        refuse(path, "ElementDataFile = LIST: line " + std::to_string(k + 1) + " after it is not a file name");
  } else if (dataFile.find('%') != std::string::npos) {
    // MetaIO reads a fifth word as part of a file name with blanks and then takes other words for
    // first and step than these: such a pattern is not read the way it looks.
    if (w.size() > 4)
      refuse(path, "ElementDataFile = " + shownValue(dataFile) + ": a pattern is 'name%03d.raw first last step' "
                   "(no blanks in the name); rename the files");
    names = patternFiles(path, "ElementDataFile", dataFile, w, size[2], false);
  } else {
    return {};
  }
  for (std::string& name : names) {
    std::error_code ec;
    if (!fs::is_regular_file(besideHeader(path, name), ec))
      refuse(path, "data file " + shownValue(name) + " is missing; put it beside the header or fix ElementDataFile");
    name = besideHeader(path, name);
  }
  return names;
}

// MetaIO trusts its header: NDims outside 1..10 makes it loop or index out of its arrays, a DimSize of 0
// divides by zero, NaN/zero spacings become 1 mm, a pattern becomes a printf format. So the header is
// checked here, key by key, before MetaIO parses it.
void checkMetaHeader(const std::string& path) {
  const TextHeader h = readTextHeader(path, '=', "elementdatafile");
  if (h.tooLong) refuse(path, "MetaImage header is longer than 1 MiB without its ElementDataFile key (a damaged value?)");
  if (!h.complete)
    refuse(path, "MetaImage header has no ElementDataFile key (misspelled?), so where its voxels are is unknown; "
                 "the last header key must be ElementDataFile = LOCAL or a file name");
  auto field = [&](const char* key) -> std::optional<std::string> {
    const auto it = h.fields.find(key);
    if (it == h.fields.end()) return std::nullopt;
    return it->second;
  };
  const auto ndims = field("ndims");
  if (!ndims) refuse(path, "MetaImage header has no NDims key; a CT has NDims = 3");
  const auto n = toInteger(trim(*ndims));
  if (!n || *n != 3) refuse(path, "NDims = " + shownValue(*ndims) + ": not a 3-D volume (a CT has NDims = 3)");
  const auto dimSize = field("dimsize");
  if (!dimSize) refuse(path, "MetaImage header has no DimSize key (the voxels along x, y and z)");
  {
    const auto w = words(*dimSize);
    for (std::size_t i = 0; i < 3; ++i) {
      const auto x = i < w.size() ? toInteger(w[i]) : std::nullopt;
      if (w.size() != 3 || !x || *x < 1) // 0 divides by zero in MetaIO
        refuse(path, "DimSize = " + shownValue(*dimSize) + " is not 3 positive whole numbers (damaged header?)");
    }
    requireVoxelCount(path, "DimSize", double(*toInteger(w[0])) * double(*toInteger(w[1])) * double(*toInteger(w[2])));
  }
  // Keys as MetaIO spells them; the header map holds them in lower case.
  auto named = [&](const std::string& key) -> std::optional<std::pair<std::string, std::string>> {
    const auto v = field(lower(key).c_str());
    if (!v) return std::nullopt;
    return std::make_pair(key, *v);
  };
  if (!field("elementspacing") && !field("elementsize"))
    refuse(path, "MetaImage header has no ElementSpacing, so the voxel size is unknown (the reader would assume "
                 "1 mm); add 'ElementSpacing = x y z' in mm");
  for (const char* key : {"ElementSpacing", "ElementSize"})
    if (const auto kv = named(key))
      for (double mm : numbersOf(path, kv->first, kv->second, 3)) requireSpacing(path, kv->first + " holds", mm);
  for (const char* key : {"Offset", "Position", "Origin"})
    if (const auto kv = named(key))
      for (double x : numbersOf(path, kv->first, kv->second, 3))
        if (!std::isfinite(x)) refuse(path, kv->first + " = " + shownValue(kv->second) + " is not a finite position");
  for (const char* key : {"TransformMatrix", "Rotation", "Orientation"})
    if (const auto kv = named(key)) {
      const auto m = numbersOf(path, kv->first, kv->second, 9);
      for (double x : m)
        if (!std::isfinite(x)) refuse(path, kv->first + " = " + shownValue(kv->second) + " is not finite");
      for (int c = 0; c < 3; ++c)
        if (!(scaledNorm(&m[std::size_t(3 * c)], 3) > 0))
          refuse(path, kv->first + " = " + shownValue(kv->second) + " has a zero axis (damaged header?)");
    }
  // One number per voxel of a type MetaIO knows: arrays, vectors and strings are not a CT (and an
  // unknown type leaves MetaIO without an element size).
  {
    const std::string type = trim(field("elementtype").value_or(""));
    static const char* const kScalarTypes[] = {"MET_CHAR", "MET_UCHAR", "MET_SHORT", "MET_USHORT", "MET_INT",
                                               "MET_UINT", "MET_LONG", "MET_ULONG", "MET_LONG_LONG",
                                               "MET_ULONG_LONG", "MET_FLOAT", "MET_DOUBLE"};
    if (std::none_of(std::begin(kScalarTypes), std::end(kScalarTypes), [&](const char* t) { return type == t; }))
      refuse(path, "ElementType = " + shownValue(type) + " is not one number per voxel (MET_SHORT, MET_FLOAT, ...)");
  }
  // Only a binary image: ObjectType names what the file holds (a Mesh, Tube, ... is no volume), and text voxels
  // (BinaryData = False) are parsed by MetaIO without any check of their count or values (binary bytes read as
  // text became a volume without a word).
  if (const auto v = field("objecttype"); v && lower(trim(*v)) != "image")
    refuse(path, "ObjectType = " + shownValue(*v) + ": not an image (a CT has ObjectType = Image)");
  if (const auto v = field("binarydata"); v && lower(trim(*v)) != "true")
    refuse(path, "BinaryData = " + shownValue(*v) + ": text (ASCII) voxels are not read, as their values cannot be "
                 "checked; save the volume as binary MetaImage (BinaryData = True)");
  if (const auto v = field("binarydatabyteordermsb"); v && lower(trim(*v)) != "true" && lower(trim(*v)) != "false")
    refuse(path, "BinaryDataByteOrderMSB = " + shownValue(*v) + " is neither True nor False, so the byte order is unknown");
  if (const auto v = field("elementbyteordermsb"); v && lower(trim(*v)) != "true" && lower(trim(*v)) != "false")
    refuse(path, "ElementByteOrderMSB = " + shownValue(*v) + " is neither True nor False, so the byte order is unknown");
  if (const auto v = field("elementnumberofchannels")) {
    const auto c = toInteger(trim(*v));
    if (!c || *c != 1)
      refuse(path, "ElementNumberOfChannels = " + shownValue(*v) + ": a CT has one value per voxel");
  }
  if (const auto v = field("headersize")) {
    const auto b = toInteger(trim(*v));
    if (!b || *b < -1) refuse(path, "HeaderSize = " + shownValue(*v) + " must be -1 or a byte count >= 0");
  }
  if (words(field("elementdatafile").value_or("")).empty())
    refuse(path, "ElementDataFile has no value; it must be LOCAL or a file name");
  (void)metaDataFiles(path, h);
}

void checkMetaPayload(const std::string& path, std::uintmax_t imageBytes) {
  const TextHeader h = readTextHeader(path, '=', "elementdatafile");
  const std::string dataFile = h.fields.at("elementdatafile");
  const bool compressed = h.fields.count("compresseddata") && lower(h.fields.at("compresseddata")) == "true";
  std::uintmax_t offset = 0;
  if (h.fields.count("headersize")) offset = std::uintmax_t(std::max(0LL, toInteger(trim(h.fields.at("headersize"))).value_or(0)));
  const auto files = metaDataFiles(path, h);
  if (!files.empty()) {
    for (const std::string& f : files)
      requireDataFile(path, f, compressed ? 0 : offset, compressed ? Packing::Zlib : Packing::Raw,
                      imageBytes / files.size());
    return;
  }
  const bool local = lower(dataFile) == "local";
  const std::string data = local ? path : besideHeader(path, dataFile);
  // Compressed: MetaIO inflates CompressedDataSize bytes and leaves the voxels those do not reach as they were,
  // without a word (a size 100 bytes short, or none, read a different volume). It must be the compressed
  // bytes exactly: the rest of the file after the header, or the whole data file (checked to exist first, so
  // a missing one is named as such).
  if (!local) requireDataFile(path, data, compressed ? 0 : offset, compressed ? Packing::Zlib : Packing::Raw, imageBytes);
  if (compressed) {
    const std::uintmax_t size = fileSize(data), start = local ? h.dataOffset : 0;
    const std::uintmax_t stored = size > start ? size - start : 0;
    const auto given = h.fields.count("compresseddatasize") ? toInteger(trim(h.fields.at("compresseddatasize")))
                                                            : std::nullopt;
    if (!given || *given < 0 || std::uintmax_t(*given) != stored)
      refuse(path, "CompressedDataSize = " +
                       (h.fields.count("compresseddatasize") ? shownValue(h.fields.at("compresseddatasize")) : "(missing)") +
                       " must be the " + std::to_string(stored) + " compressed bytes the data holds (the reader "
                       "inflates only that many and leaves the other voxels unset); export the volume again");
  }
  if (!local) return;
  if (compressed) requireBytes(path, inflatedBytes(data, h.dataOffset, false), imageBytes);
  else {
    const auto size = fileSize(data);
    requireBytes(path, size > h.dataOffset ? size - h.dataOffset : 0, imageBytes);
    // HeaderSize > 0 moves the start of the voxels: the file must hold them after it (999999999 read zeros).
    if (offset > 0 && !(size >= offset && size - offset >= imageBytes))
      refuse(path, "HeaderSize = " + std::to_string(offset) + " puts the voxels past the end of the file (" +
                       std::to_string(size) + " bytes, " + std::to_string(imageBytes) + " of voxels); fix HeaderSize "
                       "or export the volume again");
  }
}

// ---- NRRD ----

// The vectors of a NRRD "space directions" or "space origin" value: "(x,y,z) (x, y, z) none ..." (blanks
// inside the brackets allowed, as teem allows them).
std::vector<std::optional<std::vector<double>>> nrrdVectors(const std::string& path, const std::string& key,
                                                            const std::string& value) {
  std::vector<std::optional<std::vector<double>>> out;
  std::size_t i = 0;
  auto bad = [&](const char* what) { refuse(path, key + ": " + shownValue(value) + " " + what + " (damaged header?)"); };
  while (i < value.size()) {
    if (std::isspace(static_cast<unsigned char>(value[i]))) {
      ++i;
      continue;
    }
    if (value.compare(i, 4, "none") == 0) {
      out.emplace_back(std::nullopt);
      i += 4;
      continue;
    }
    if (value[i] != '(') bad("is not a list of (x,y,z) vectors");
    const auto close = value.find(')', i);
    if (close == std::string::npos) bad("has a vector without its ')'");
    std::vector<double> v;
    std::stringstream parts(value.substr(i + 1, close - i - 1));
    std::string part;
    while (std::getline(parts, part, ',')) {
      const auto x = toNumber(trim(part));
      if (!x) bad("holds something that is not a number");
      v.push_back(*x);
    }
    if (v.empty()) bad("holds an empty vector");
    out.emplace_back(std::move(v));
    i = close + 1;
  }
  return out;
}

// The files a NRRD's data is in when there are several ("data file: LIST [subdim]" with one name per line
// after it, or "data file: name%03d.raw first last step [subdim]"), beside the header; empty for one file or
// none. Throws unless there is exactly one existing file per sub-volume (teem: per slice of the last axis
// unless subdim says otherwise). dimension and sizes were checked before (checkNrrdHeader).
std::vector<std::string> nrrdDataFiles(const std::string& path, const TextHeader& h) {
  const auto at = h.fields.count("data file") ? h.fields.find("data file") : h.fields.find("datafile");
  if (at == h.fields.end()) return {};
  const std::string& dataFile = at->second;
  const auto w = words(dataFile);
  const bool list = !w.empty() && w[0] == "LIST";
  if (!list && dataFile.find('%') == std::string::npos) return {};
  std::vector<long long> sizes;
  for (const std::string& t : words(h.fields.count("sizes") ? h.fields.at("sizes") : ""))
    sizes.push_back(toInteger(t).value_or(1));
  long long subdim = static_cast<long long>(sizes.size()) - 1;
  const std::size_t subdimAt = list ? 1 : 4;
  if (w.size() > subdimAt) {
    const auto d = toInteger(w[subdimAt]);
    if (!d || *d < 1 || *d > static_cast<long long>(sizes.size()))
      refuse(path, "data file: " + shownValue(dataFile) + ": the sub-dimension must be 1.." + std::to_string(sizes.size()));
    subdim = *d;
  }
  long long needed = 1;
  for (std::size_t a = std::size_t(std::max(0LL, subdim)); a < sizes.size(); ++a) needed *= sizes[a];
  std::vector<std::string> names;
  if (list) {
    std::size_t blankLines = 0;
    names = linesAfterKey(path, at->first, ':', &blankLines);
    // Exactly one name per piece: teem refuses a longer list ("expected 16 filenames but got 17"), with the
    // empty line a header's blank line ends with counted as a name.
    if (static_cast<long long>(names.size()) != needed)
      refuse(path, "data file: LIST names " + std::to_string(names.size()) + " files, but sizes need " +
                       std::to_string(needed) + "; list exactly one file per slice");
    if (blankLines > 0)
      refuse(path, "data file: LIST is followed by a blank line, which this build's NRRD reader takes for one more "
                   "file name; end the header with the last file name");
  } else {
    names = patternFiles(path, "data file", dataFile, w, needed, true);
  }
  for (std::string& name : names) {
    std::error_code ec;
    if (name.empty() || !fs::is_regular_file(besideHeader(path, name), ec))
      refuse(path, "data file " + shownValue(name) + " is missing; put it beside the header or fix the header");
    name = besideHeader(path, name);
  }
  return names;
}

// NRRD fields ITK's NRRD reader uses for the geometry, checked in the file: it replaces a NaN or zero
// spacing by 1 mm, and takes the length of each space direction as the spacing (an overflowing length
// became a zero direction). bzip2 data this build's reader cannot decode; data file patterns become printf
// formats in teem.
void checkNrrdHeader(const std::string& path) {
  const TextHeader h = readTextHeader(path, ':', "");
  if (h.tooLong) refuse(path, "NRRD header is longer than 1 MiB without its end (a damaged value?)");
  auto field = [&](std::initializer_list<const char*> keys) -> std::optional<std::string> {
    for (const char* key : keys) {
      const auto it = h.fields.find(key);
      if (it != h.fields.end()) return it->second;
    }
    return std::nullopt;
  };
  if (const auto e = field({"encoding"})) {
    const std::string encoding = lower(*e);
    if (encoding == "bzip2" || encoding == "bz2")
      refuse(path, "NRRD data is bzip2-compressed, which this program's NRRD reader cannot decompress; save it with "
                   "gzip or raw encoding (for example: unu save -e gzip -f nrrd)");
  }
  // dimension and sizes: teem allocates and loops by them; a count that is not a small positive integer is
  // damage (a CT is 3-D; 16 is teem's own limit).
  const auto dimension = field({"dimension"});
  if (!dimension) refuse(path, "NRRD header has no dimension field");
  const auto axes = toInteger(trim(*dimension));
  if (!axes || *axes < 1 || *axes > 16) refuse(path, "dimension: " + shownValue(*dimension) + " is not 1..16 axes (a CT has 3)");
  if (*axes != 3)
    refuse(path, "not a 3-D volume (dimension: " + std::to_string(*axes) + "); a CT has 3 axes and one value per voxel");
  {
    const auto sizesField = field({"sizes"});
    if (!sizesField) refuse(path, "NRRD header has no sizes field");
    const auto w = words(*sizesField);
    bool good = static_cast<long long>(w.size()) == *axes;
    double voxels = 1;
    for (const std::string& t : w) {
      good = good && toInteger(t).value_or(0) >= 1;
      voxels *= double(toInteger(t).value_or(0));
    }
    if (!good)
      refuse(path, "sizes: " + shownValue(*sizesField) + " is not " + std::to_string(*axes) +
                       " positive whole numbers (one per axis of dimension)");
    requireVoxelCount(path, "sizes", voxels);
  }
  // No spacing at all: the reader would assume 1 mm, a guess that silently scales every distance.
  if (!field({"spacings"}) && !field({"space directions"}))
    refuse(path, "NRRD header has neither spacings nor space directions, so the voxel size is unknown (the reader "
                 "would assume 1 mm); add 'spacings: x y z' in mm");
  // teem reads "space directions" and "space origin" only after "space" (or "space dimension") has named the
  // space: a header with them first (hand-written; session 6's hostile cases) failed in the reader as "cannot
  // read (corrupt or truncated ...)", which said nothing of the order.
  {
    const auto position = [&](const char* key) {
      return std::size_t(std::find(h.order.begin(), h.order.end(), key) - h.order.begin());
    };
    const std::size_t space = std::min(position("space"), position("space dimension"));
    for (const char* key : {"space directions", "space origin"})
      if (position(key) < h.order.size() && position(key) < space)
        refuse(path, std::string(key) + " comes before any 'space:' or 'space dimension:' line, and the NRRD reader "
                                        "needs the space named first; put 'space: left-posterior-superior' above it");
  }
  if (const auto v = field({"spacings"})) {
    if (words(*v).size() != std::size_t(*axes))
      refuse(path, "spacings: " + shownValue(*v) + " is not one spacing per axis (" + std::to_string(*axes) + ")");
  }
  if (const auto v = field({"spacings"}))
    for (const std::string& w : words(*v)) {
      const auto x = toNumber(w);
      if (!x) refuse(path, "spacings: " + shownValue(*v) + " holds something that is not a number");
      requireSpacing(path, "spacings: a spacing of", *x);
    }
  if (const auto v = field({"space directions"}))
    for (const auto& d : nrrdVectors(path, "space directions", *v)) {
      // "none" marks a non-spatial axis; all three of a CT's axes are spatial (the reader would give a
      // "none" axis 1 mm).
      if (!d)
        refuse(path, "space directions: " + shownValue(*v) + " has an axis that is 'none' (not spatial); a CT's three "
                     "axes all have a direction");
      for (double x : *d)
        if (!std::isfinite(x)) refuse(path, "space directions: " + shownValue(*v) + " is not finite (damaged header?)");
      requireSpacing(path, "space directions: a direction of length", scaledNorm(d->data(), int(d->size())));
    }
  if (const auto v = field({"space origin"}))
    for (const auto& d : nrrdVectors(path, "space origin", *v))
      for (double x : d.value_or(std::vector<double>{}))
        if (!std::isfinite(x)) refuse(path, "space origin: " + shownValue(*v) + " is not a finite position");
  // byte skip: -1 means "the data are the file's last bytes", which the format allows for raw data only; any
  // other negative skip is no position (teem read such files without a word). line skip: a count.
  for (const char* key : {"byte skip", "byteskip"})
    if (const auto v = field({key})) {
      const auto skip = toInteger(trim(*v));
      const std::string encoding = lower(trim(field({"encoding"}).value_or("raw")));
      if (!skip || *skip < -1 || (*skip == -1 && encoding != "raw"))
        refuse(path, std::string(key) + ": " + shownValue(*v) + " must be a byte count >= 0, or -1 (data at the end) "
                     "with raw encoding only");
    }
  for (const char* key : {"line skip", "lineskip"})
    if (const auto v = field({key})) {
      const auto skip = toInteger(trim(*v));
      if (!skip || *skip < 0) refuse(path, std::string(key) + ": " + shownValue(*v) + " must be a line count >= 0");
    }
  (void)nrrdDataFiles(path, h);
}

void checkNrrdPayload(const std::string& path, std::uintmax_t imageBytes) {
  const TextHeader h = readTextHeader(path, ':', "");
  const std::string encoding = lower(h.fields.count("encoding") ? h.fields.at("encoding") : "raw");
  std::string dataFile = h.fields.count("data file") ? h.fields.at("data file")
                         : h.fields.count("datafile") ? h.fields.at("datafile") : "";
  // Skips: left to ITK.
  for (const char* key : {"line skip", "lineskip", "byte skip", "byteskip"})
    if (h.fields.count(key) && trim(h.fields.at(key)) != "0") return;
  const Packing packing = encoding == "gzip" || encoding == "gz" ? Packing::Gzip : Packing::Raw;
  if (encoding != "raw" && packing != Packing::Gzip) return; // text encodings: the reader counts the values
  const auto files = nrrdDataFiles(path, h);
  if (!files.empty()) {
    for (const std::string& f : files) requireDataFile(path, f, 0, packing, imageBytes / files.size());
    return;
  }
  if (dataFile.empty() && !h.complete) refuse(path, "NRRD header has no end (no blank line)");
  if (!dataFile.empty()) {
    requireDataFile(path, besideHeader(path, dataFile), 0, packing, imageBytes);
    return;
  }
  if (packing == Packing::Gzip) requireBytes(path, inflatedBytes(path, h.dataOffset, true), imageBytes);
  else {
    const auto size = fileSize(path);
    requireBytes(path, size > h.dataOffset ? size - h.dataOffset : 0, imageBytes);
  }
}

// ---- NIfTI-1 ----

// Bytes per voxel of a NIfTI datatype code; 0 for a code nifti_io does not know.
std::uintmax_t niftiVoxelBytes(int datatype) {
  switch (datatype) {
  case 2: case 256: return 1;           // uint8, int8
  case 4: case 512: return 2;           // int16, uint16
  case 8: case 16: case 768: return 4;  // int32, float32, uint32
  case 64: case 1024: case 1280: case 32: return 8; // float64, int64, uint64, complex64
  case 128: return 3;                   // rgb24
  case 2304: return 4;                  // rgba32
  case 1536: case 1792: return 16;      // float128, complex128
  case 2048: return 32;                 // complex256
  default: return 0;
  }
}

// A NIfTI-1 header, checked field by field before nifti_io and ITK see it (byte offsets from the standard;
// numbers in the header's byte order, which sizeof_hdr = 348 at byte 0 tells):
//  * dim (40): 1..7 axes, each >= 1; datatype (70) known;
//  * pixdim (76): the spacings; nifti_io makes a NaN, infinite, zero or negative one 1 mm without a word;
//  * the qform (quatern_b/c/d, qoffset: 256..279) and sform (srow_x/y/z: 280..327) when their codes (252,
//    254) say they are used: ITK asserts on NaN in them, and a zero axis is no orientation;
//  * vox_offset (108): where the voxels start; negative, fractional or past the end of the file reads
//    other bytes (or zeros) as voxels, so the file (or the pair's .img) must hold vox_offset + the voxels;
//  * scl_slope/scl_inter (112, 116): a NaN or infinite factor makes every HU unknown (nifti_io would skip a
//    NaN slope and hand the raw values on as HU);
//  * floating-point voxels (datatype 16 or 64): nifti_io sets NaN and infinite voxels to 0 as it reads them,
//    silently, so they are looked for here first.
void checkNifti(const std::string& path) {
  gzFile in = gzopen(path.c_str(), "rb"); // reads plain files too
  if (!in) refuse(path, "cannot open");
  struct Closer {
    gzFile f;
    ~Closer() { gzclose(f); }
  } closer{in};
  unsigned char header[kNiftiHeaderBytes];
  const int got = gzread(in, header, unsigned(kNiftiHeaderBytes));
  if (got != int(kNiftiHeaderBytes))
    refuse(path, "NIfTI header is cut short (" + std::to_string(std::max(got, 0)) + " of 348 bytes); export it again");
  std::uint32_t sizeofHdr = 0;
  std::memcpy(&sizeofHdr, header, 4);
  const std::uint32_t swappedSize = ((sizeofHdr & 0xffu) << 24) | ((sizeofHdr & 0xff00u) << 8) |
                                    ((sizeofHdr >> 8) & 0xff00u) | (sizeofHdr >> 24);
  if (sizeofHdr != kNiftiHeaderBytes && swappedSize != kNiftiHeaderBytes) {
    // NIfTI-2 (sizeof_hdr 540, magic "n+2" or "ni2" at byte 4): nifti_io checks it. Any other size is damage:
    // nifti_io took a NIfTI-1 layout with sizeof_hdr 540 for a volume.
    const std::string magic2(reinterpret_cast<const char*>(header + 4), 3);
    if ((sizeofHdr == 540 || swappedSize == 540) && (magic2 == "n+2" || magic2 == "ni2")) return;
    refuse(path, "NIfTI sizeof_hdr is " + std::to_string(sizeofHdr) + ", neither NIfTI-1's 348 nor NIfTI-2's 540 with "
                 "its magic (damaged header, or not NIfTI); export it again");
  }
  const bool swapped = sizeofHdr != kNiftiHeaderBytes;
  auto field = [&](std::size_t at, std::size_t bytes, void* out) {
    unsigned char b[8];
    std::memcpy(b, header + at, bytes);
    if (swapped) std::reverse(b, b + bytes);
    std::memcpy(out, b, bytes);
  };
  auto floatAt = [&](std::size_t at) {
    float f = 0;
    field(at, 4, &f);
    return double(f);
  };
  auto shortAt = [&](std::size_t at) {
    std::int16_t v = 0;
    field(at, 2, &v);
    return int(v);
  };
  int dims[8];
  for (int i = 0; i < 8; ++i) dims[i] = shortAt(40 + 2 * std::size_t(i));
  if (dims[0] < 1 || dims[0] > 7)
    refuse(path, "NIfTI dim[0] = " + std::to_string(dims[0]) + " is not a number of axes (1..7; damaged header?)");
  for (int i = 1; i <= dims[0]; ++i)
    if (dims[i] < 1)
      refuse(path, "NIfTI dim[" + std::to_string(i) + "] = " + std::to_string(dims[i]) + " is not a size (damaged header?)");
  const int datatype = shortAt(70);
  const std::uintmax_t voxelBytes = niftiVoxelBytes(datatype);
  if (voxelBytes == 0) refuse(path, "NIfTI datatype " + std::to_string(datatype) + " is not a known voxel type (damaged header?)");
  for (int i = 1; i <= std::min(dims[0], 3); ++i)
    requireSpacing(path, "NIfTI pixdim[" + std::to_string(i) + "] =", floatAt(76 + 4 * std::size_t(i)));
  // bitpix (72) must match the datatype: nifti_io replaces a wrong one silently, so which of the two was meant
  // is unknown.
  if (const int bitpix = shortAt(72); std::uintmax_t(std::max(bitpix, 0)) != voxelBytes * 8)
    refuse(path, "NIfTI bitpix " + std::to_string(bitpix) + " does not match datatype " + std::to_string(datatype) + " (" +
                     std::to_string(voxelBytes * 8) + " bits per voxel; damaged header?)");
  const int qformCode = shortAt(252), sformCode = shortAt(254);
  if (qformCode > 0) {
    for (std::size_t at = 256; at < 280; at += 4)
      if (!std::isfinite(floatAt(at)))
        refuse(path, "NIfTI qform (quatern_b/c/d, qoffset) is not finite (damaged header?); the orientation is unknown");
    // A unit quaternion has b^2 + c^2 + d^2 <= 1 (a = sqrt(1 - that)); nifti_io rescales a larger (b, c, d) to
    // length 1 without a word, a rotation nobody wrote. 1e-5 leaves room for the floats' rounding.
    const double b = floatAt(256), c = floatAt(260), d = floatAt(264);
    if (!(b * b + c * c + d * d <= 1.0 + 1e-5))
      refuse(path, "NIfTI qform quaternion (quatern_b/c/d " + number(b) + ", " + number(c) + ", " + number(d) +
                       ") has b^2 + c^2 + d^2 > 1, so it is no rotation (damaged header?)");
  }
  if (sformCode > 0) {
    double m[12];
    for (std::size_t k = 0; k < 12; ++k) m[k] = floatAt(280 + 4 * k);
    for (double x : m)
      if (!std::isfinite(x)) refuse(path, "NIfTI sform (srow_x/y/z) is not finite (damaged header?); the orientation is unknown");
    // Each axis scaled to unit length (overflow-safe), then the determinant: parallel axes are no orientation.
    double u[3][3];
    for (int c = 0; c < 3; ++c) {
      const double axis[3] = {m[c], m[4 + c], m[8 + c]};
      const double length = scaledNorm(axis, 3);
      if (!(length > 0) || !std::isfinite(length)) refuse(path, "NIfTI sform has a zero axis (damaged header?)");
      for (int r = 0; r < 3; ++r) u[c][r] = axis[r] / length;
    }
    const double det = u[0][0] * (u[1][1] * u[2][2] - u[1][2] * u[2][1]) - u[0][1] * (u[1][0] * u[2][2] - u[1][2] * u[2][0]) +
                       u[0][2] * (u[1][0] * u[2][1] - u[1][1] * u[2][0]);
    if (!(std::abs(det) > 1e-6)) refuse(path, "NIfTI sform's axes are parallel (singular; damaged header?)");
  }
  const double slope = floatAt(112), intercept = floatAt(116);
  if (!std::isfinite(slope) || !std::isfinite(intercept))
    refuse(path, "NIfTI scaling scl_slope " + number(slope) + ", scl_inter " + number(intercept) +
                     " is not finite, so no voxel's HU is known (damaged header?)");
  const double voxOffset = floatAt(108);
  const std::string magic(reinterpret_cast<const char*>(header + 344), 3);
  const bool pair = magic != "n+1";
  // A single .nii(.gz) file must say it is NIfTI-1 ("n+1"): without the magic nifti_io reads it as Analyze
  // 7.5, whose orientation fields mean something else.
  {
    const std::string name = lower(fs::path(path).filename().string());
    const bool singleFile = name.size() > 4 && (name.substr(name.size() - 4) == ".nii" ||
                                                (name.size() > 7 && name.substr(name.size() - 7) == ".nii.gz"));
    if (singleFile && pair)
      refuse(path, "NIfTI magic is " + shownValue(std::string(reinterpret_cast<const char*>(header + 344),
                                                               strnlen(reinterpret_cast<const char*>(header + 344), 4))) +
                       ", not 'n+1' (a damaged header, or an Analyze file named .nii); export it again as NIfTI");
  }
  const double minOffset = pair ? 0.0 : double(kNiftiHeaderBytes);
  if (!(voxOffset >= minOffset && voxOffset < 9e15) || voxOffset != std::floor(voxOffset))
    refuse(path, "NIfTI vox_offset " + number(voxOffset) + " is not a byte position of the voxels (a whole number >= " +
                     number(minOffset) + "; damaged header?)");
  double voxelCount = 1;
  for (int i = 1; i <= dims[0]; ++i) voxelCount *= double(dims[i]);
  requireVoxelCount(path, "NIfTI dim", voxelCount);
  const std::uintmax_t voxels = std::uintmax_t(voxelCount);
  const std::uintmax_t needed = std::uintmax_t(voxOffset) + voxels * voxelBytes;
  if (pair) {
    // The pixels of a .hdr/.img pair are in the .img (or .img.gz) beside it.
    const std::string ext = fs::path(path).extension().string();
    if (lower(ext) != ".hdr") return; // a single file without the n+1 magic: nifti_io decides what it is
    std::string img = path.substr(0, path.size() - 4) + (ext == ".HDR" ? ".IMG" : ".img");
    std::error_code ec;
    if (!fs::exists(img, ec) && fs::exists(img + ".gz", ec)) img += ".gz";
    if (!fs::is_regular_file(img, ec))
      refuse(path, "the .img file of this .hdr/.img pair is missing; put it beside the header");
    std::ifstream probe(img, std::ios::binary);
    unsigned char m2[2] = {0, 0};
    probe.read(reinterpret_cast<char*>(m2), 2);
    const bool gz = m2[0] == 0x1f && m2[1] == 0x8b;
    const std::uintmax_t available = gz ? inflatedBytes(img, 0, true) : fileSize(img);
    if (available < needed)
      refuse(path, "its .img file holds " + std::to_string(available) + " bytes, " + std::to_string(needed) +
                       " expected (vox_offset plus the voxels; truncated?); export the volume again");
    return;
  }
  unsigned char m2[2] = {0, 0};
  {
    std::ifstream probe(path, std::ios::binary);
    probe.read(reinterpret_cast<char*>(m2), 2);
  }
  const bool gz = m2[0] == 0x1f && m2[1] == 0x8b;
  const std::uintmax_t available = gz ? inflatedBytes(path, 0, true) : fileSize(path);
  if (available < needed)
    refuse(path, "holds " + std::to_string(available) + " bytes, " + std::to_string(needed) +
                     " expected (vox_offset " + number(voxOffset) + " plus the voxels; truncated, or vox_offset past "
                     "the end?); export the volume again");
  const std::size_t bytes = datatype == 16 ? 4 : datatype == 64 ? 8 : 0;
  if (bytes == 0) return;
  gzseek(in, z_off_t(voxOffset), SEEK_SET);
  std::vector<unsigned char> chunk(bytes * 65536);
  std::uintmax_t index = 0;
  while (index < voxels) {
    const std::size_t want = std::size_t(std::min<std::uintmax_t>(65536, voxels - index));
    const int read = gzread(in, chunk.data(), unsigned(want * bytes));
    if (read <= 0) break;
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
        const std::uintmax_t nx = std::uintmax_t(dims[1]), ny = std::uintmax_t(dims[0] >= 2 ? dims[2] : 1);
        refuse(path, "voxel (" + std::to_string(index % nx) + "," + std::to_string(index / nx % ny) + "," +
                         std::to_string(index / (nx * ny)) + ") is " + (std::isnan(x) ? "NaN" : "infinite") +
                         "; a CT must hold finite values");
      }
    }
  }
}

} // namespace

std::string shownValue(const std::string& value) {
  std::string out;
  for (unsigned char c : value) {
    if (out.size() >= 40) {
      out += "...";
      break;
    }
    out += (c < 32 || c == 127) ? '?' : char(c);
  }
  return "'" + out + "'";
}

double scaledNorm(const double* v, int n) {
  double largest = 0;
  for (int i = 0; i < n; ++i) largest = std::max(largest, std::abs(v[i]));
  if (!(largest > 0) || !std::isfinite(largest)) return largest;
  double sum = 0;
  for (int i = 0; i < n; ++i) sum += (v[i] / largest) * (v[i] / largest);
  return largest * std::sqrt(sum);
}

void checkHeaderBeforeItk(const std::string& path, VolumeFormat format) {
  switch (format) {
  case VolumeFormat::Nrrd: checkNrrdHeader(path); break;
  case VolumeFormat::MetaImage: checkMetaHeader(path); break;
  case VolumeFormat::Nifti: checkNifti(path); break;
  }
}

void checkPayload(const std::string& path, VolumeFormat format, std::uintmax_t imageBytes) {
  switch (format) {
  case VolumeFormat::Nrrd: checkNrrdPayload(path, imageBytes); break;
  case VolumeFormat::MetaImage: checkMetaPayload(path, imageBytes); break;
  case VolumeFormat::Nifti: break; // checkNifti counted the bytes from the header itself
  }
}

} // namespace cementsph::imaging::detail
