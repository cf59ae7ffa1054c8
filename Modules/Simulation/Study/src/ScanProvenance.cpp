#include "cementsph/study/ScanProvenance.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <system_error>

namespace cementsph::study {

namespace {

namespace fs = std::filesystem;

bool phantomRecordIn(const fs::path& folder) {
  std::error_code ec;
  const fs::path truth = folder / "truth.json";
  if (!fs::is_regular_file(truth, ec)) return false;
  std::ifstream in(truth);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object() || !j.contains("command") || !j["command"].is_string()) return false;
  return j["command"].get<std::string>().rfind("cementsph phantom", 0) == 0;
}

} // namespace

bool madeByPhantom(const fs::path& given) {
  std::error_code ec;
  const fs::path scan = given.filename().empty() ? given.parent_path() : given; // "pre_dicom/" as "pre_dicom"
  const fs::path folder = scan.parent_path().empty() ? fs::path(".") : scan.parent_path();
  if (fs::is_directory(scan, ec)) return phantomRecordIn(scan) || phantomRecordIn(folder);
  return phantomRecordIn(folder);
}

std::string postScanLabel(const fs::path& scan) {
  return madeByPhantom(scan) ? "post (phantom, simulated)" : "post (CT)";
}

std::string referenceScansLabel(const std::vector<std::string>& scans) {
  for (const std::string& s : scans)
    if (madeByPhantom(s)) return "reference (phantom, simulated)";
  return "reference (CT)";
}

} // namespace cementsph::study
