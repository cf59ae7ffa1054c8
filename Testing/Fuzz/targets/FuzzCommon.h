// Shared by the libFuzzer targets (scripts/ci-sanitizers.sh builds them): a private temporary folder per
// fuzzing process, the input written there under a fixed name, and the oracle for a refusal. The checks
// under test take file paths, so each input is a file; nothing here calls ITK, VTK or any library reader.
#pragma once

#include <zlib.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

namespace cementsph::fuzz {

// The folder, made once per process (libFuzzer's -fork/-jobs workers each get their own) and removed at exit.
inline const std::string& workDir() {
  static const std::string dir = [] {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base && *base ? base : "/tmp") + "/cementsph-fuzz-XXXXXX";
    if (!mkdtemp(pattern.data())) {
      std::perror("mkdtemp");
      std::abort();
    }
    static std::string removeAtExit;
    removeAtExit = pattern;
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(removeAtExit, ec);
    });
    return pattern;
  }();
  return dir;
}

inline std::string writeFile(const std::string& name, const unsigned char* data, std::size_t size) {
  const std::string path = workDir() + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path;
}

// Data files a header may name beside it (the seeds use them): raw bytes, a gzip member, a zlib stream and
// three numbered slices, each 4096 bytes of data. Written once per process.
inline void writeCompanions() {
  static const bool done = [] {
    std::string raw(4096, '\0');
    for (std::size_t i = 0; i < raw.size(); ++i) raw[i] = char(i * 31 % 251);
    auto put = [](const std::string& name, const std::string& bytes) {
      writeFile(name, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
    };
    put("data.raw", raw);
    put("slice0.raw", raw);
    put("slice1.raw", raw);
    put("slice2.raw", raw);
    gzFile gz = gzopen((workDir() + "/data.raw.gz").c_str(), "wb");
    if (!gz || gzwrite(gz, raw.data(), unsigned(raw.size())) != int(raw.size()) || gzclose(gz) != Z_OK) std::abort();
    uLongf packedSize = compressBound(uLong(raw.size()));
    std::string packed(packedSize, '\0');
    if (compress(reinterpret_cast<Bytef*>(packed.data()), &packedSize, reinterpret_cast<const Bytef*>(raw.data()),
                 uLong(raw.size())) != Z_OK)
      std::abort();
    packed.resize(packedSize);
    put("data.zraw", packed);
    return true;
  }();
  (void)done;
}

// A refusal is an accepted outcome when it is what the code promises: a std::exception whose message is one
// line that starts with `prefix` (the input's path) or, for a damaged data file a header names, with that
// data file's path (an existing file, followed by ": "). Anything else aborts, which libFuzzer reports as a
// finding with the input that caused it.
inline void requireReadableRefusal(const std::exception& e, const std::string& prefix, const char* target) {
  const std::string what = e.what();
  const bool oneLine = what.find('\n') == std::string::npos && what.find('\r') == std::string::npos;
  bool named = what.compare(0, prefix.size(), prefix) == 0;
  if (!named) {
    const auto colon = what.find(": ");
    std::error_code ec;
    named = colon != std::string::npos && colon > 0 && std::filesystem::is_regular_file(what.substr(0, colon), ec);
  }
  if (!oneLine || !named) {
    std::fprintf(stderr, "%s: a refusal that is not one line starting with '%s' or a data file's path:\n%s\n", target,
                 prefix.c_str(), what.c_str());
    std::abort();
  }
}

} // namespace cementsph::fuzz
