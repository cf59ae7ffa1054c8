// libFuzzer target: bytes -> a .mha file -> the checks VolumeIO makes before ITK sees the file
// (checkHeaderBeforeItk) and, for a header they pass, the payload check (checkPayload) with two image sizes.
// A refusal (std::exception, one line starting with the path of the header or of its damaged data file) is
// the accepted outcome; a crash, a hang, undefined behaviour or a leak is a finding. ITK's readers are never
// called.
#include "FuzzCommon.h"
#include "VolumeFileChecks.h"

#include <cstddef>
#include <cstdint>
#include <exception>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace cementsph::imaging::detail;
  cementsph::fuzz::writeCompanions();
  const std::string path = cementsph::fuzz::writeFile("in.mha", data, size);
  try {
    checkHeaderBeforeItk(path, VolumeFormat::MetaImage);
  } catch (const std::exception& e) {
    cementsph::fuzz::requireReadableRefusal(e, path, "metaimage_header");
    return 0;
  }
  for (std::uintmax_t imageBytes : {std::uintmax_t(1), std::uintmax_t(4096)}) {
    try {
      checkPayload(path, VolumeFormat::MetaImage, imageBytes);
    } catch (const std::exception& e) {
      cementsph::fuzz::requireReadableRefusal(e, path, "metaimage_header");
    }
  }
  return 0;
}
