// libFuzzer target: bytes -> the NIfTI checks VolumeIO makes before ITK (checkHeaderBeforeItk), twice: as a
// single file (in.nii; gzip input is read through zlib as the check reads .nii.gz) and as the header of a
// .hdr/.img pair whose .img holds the same bytes. A refusal (std::exception, one line starting with the
// path) is the accepted outcome; a crash, a hang, undefined behaviour or a leak is a finding. ITK's and
// nifti_io's readers are never called.
#include "FuzzCommon.h"
#include "VolumeFileChecks.h"

#include <cstddef>
#include <cstdint>
#include <exception>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace cementsph::imaging::detail;
  const std::string single = cementsph::fuzz::writeFile("in.nii", data, size);
  const std::string header = cementsph::fuzz::writeFile("pair.hdr", data, size);
  cementsph::fuzz::writeFile("pair.img", data, size);
  for (const std::string& path : {single, header}) {
    try {
      checkHeaderBeforeItk(path, VolumeFormat::Nifti);
      checkPayload(path, VolumeFormat::Nifti, 4096); // a no-op for NIfTI today; kept so a change is fuzzed
    } catch (const std::exception& e) {
      cementsph::fuzz::requireReadableRefusal(e, path, "nifti_header");
    }
  }
  return 0;
}
