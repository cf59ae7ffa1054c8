// Atomic output: every file is written under a temporary sibling name and renamed into place, so a
// failure never leaves a partial file behind (a rename within one directory is atomic on POSIX).
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace cementsph::imaging {

// A file that could not be written (disk full, no permission, ...): the run failed, not its input.
class OutputError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// A sibling temporary name that keeps the full extension, because ITK and VTK pick the writer by
// extension: "dir/a.nii.gz" -> "dir/a.tmp-<unique>.nii.gz".
std::string temporarySiblingPath(const std::string& path);

// The extension as the imaging code understands it, lower case, including compound ones
// (".nii.gz"); empty when there is none.
std::string fullExtension(const std::string& path);

// Calls write(temporaryPath), then renames it to path. If write throws, or the rename fails, the
// temporary is removed and an OutputError naming path is thrown. A temporary that is missing or empty
// after write counts as failed too (a writer that lost its data to a full disk without saying so).
void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

// Writes text (e.g. JSON) atomically.
void writeTextAtomically(const std::string& path, const std::string& text);

// Before a run writes into directory: removes the temporaries an interrupted run left there
// ("NAME.tmp-PID-N.EXT" of writeAtomically, "NAME.tmp-N" of older versions) and the files whose names match
// one of the numbered patterns (e.g. "particles_####.vtp": # stands for one digit), so that an earlier
// run's snapshots do not mix with the new ones. Returns how many files were removed. Only plain files
// directly in directory are touched; a missing directory removes nothing.
std::size_t removeStaleOutputs(const std::string& directory, const std::vector<std::string>& numberedPatterns);

} // namespace cementsph::imaging
