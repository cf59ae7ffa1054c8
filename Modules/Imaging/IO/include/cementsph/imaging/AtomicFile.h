// Atomic output: every file is written under a temporary sibling name and renamed into place, so a
// failure never leaves a partial file behind (a rename within one directory is atomic on POSIX).
#pragma once

#include <functional>
#include <string>

namespace cementsph::imaging {

// A sibling temporary name that keeps the full extension, because ITK and VTK pick the writer by
// extension: "dir/a.nii.gz" -> "dir/a.tmp-<unique>.nii.gz".
std::string temporarySiblingPath(const std::string& path);

// The extension as the imaging code understands it, lower case, including compound ones
// (".nii.gz"); empty when there is none.
std::string fullExtension(const std::string& path);

// Calls write(temporaryPath), then renames it to path. If write throws, or the rename fails, the
// temporary is removed and a std::runtime_error naming path is thrown.
void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

// Writes text (e.g. JSON) atomically.
void writeTextAtomically(const std::string& path, const std::string& text);

} // namespace cementsph::imaging
