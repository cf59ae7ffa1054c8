// Where a scan came from, as the pictures name it (issue 22): a post-injection scan made by `cementsph phantom`
// is simulated data and is never labelled as an experiment or a CT of one. The provenance is the phantom's own
// record: the truth.json it writes beside its scans (Data/foam-phantom, Data/vertebra-phantom), whose
// "command" is the `cementsph phantom ...` command line that made them. A scan without such a record is taken
// as the user's scan.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace cementsph::study {

// True when `scan` (a volume file, or a DICOM folder) lies in a folder whose truth.json was written by
// `cementsph phantom` (for a DICOM folder, also its parent folder's: the vertebra phantom's pre_dicom/).
// A truth.json that is missing, unreadable, not JSON or made by another command: false.
bool madeByPhantom(const std::filesystem::path& scan);

// The post-injection scan's name in pictures: "post (phantom, simulated)" or "post (CT)".
std::string postScanLabel(const std::filesystem::path& scan);

// A reference X-ray sequence's name in pictures: "reference (phantom, simulated)" when any of its volumes
// was made by the phantom, else "reference (CT)".
std::string referenceScansLabel(const std::vector<std::string>& scans);

} // namespace cementsph::study
