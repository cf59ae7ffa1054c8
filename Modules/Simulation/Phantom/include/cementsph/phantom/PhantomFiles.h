// The phantoms' files (`cementsph phantom`): truth.json, whose every key names its unit (the foam block and
// its post-injection CT, or the vertebra), and the CTs written beside it, all or nothing. The schema lives
// here, beside the phantoms it describes, so the command only parses options and prints a summary.
#pragma once

#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/phantom/FoamPhantom.h"
#include "cementsph/phantom/VertebraPhantom.h"

#include <nlohmann/json.hpp>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cementsph::phantom {

// truth.json's "foam": the block's figures, the options it was made with, its voxels and generation time.
nlohmann::json foamTruthJson(const FoamOptions& options, const FoamResult& foam, double generationS);

// truth.json's "misalignment" (with its convention) and "injection" of a post-injection CT.
nlohmann::json misalignmentTruthJson(const PostResult& post);
nlohmann::json injectionTruthJson(const PostOptions& options, const PostResult& post, double generationS);

// truth.json of the vertebra: its geometry (the anatomy variant's where on), the options it was made with, and
// the transpedicular plan the demo injects.
nlohmann::json vertebraTruthJson(const VertebraOptions& options, const VertebraResult& vertebra, double generationS);

// The injection a phantom's truth.json records under "injection" (the keys named beside each field): what a
// command needs to inject the phantom again as it was planned (the demo).
struct PhantomInjectionPlan {
  std::array<double, 3> tipMm{};                  // tip_mm
  std::optional<std::array<double, 3>> direction; // direction (the cannula's axis), when recorded
  double volumeMl = 0;                            // volume_ml
  double flowRateMlPerS = 0;                      // flow_rate_ml_per_s
  double viscosityPaS = 0;                        // viscosity_pa_s
};

// Reads phantomFolder/truth.json's "injection". Throws std::runtime_error with one line naming the file and the
// missing or malformed key (e.g. a folder that holds no phantom: "use --data-dir").
PhantomInjectionPlan readInjectionPlan(const std::filesystem::path& phantomFolder);

// The files of one phantom, written into one folder.
struct PhantomFiles {
  struct Named {
    std::string name;
    imaging::ImageType::Pointer ct;
  };
  std::vector<Named> volumes;      // NAME (.nrrd, ...), in order
  std::vector<Named> dicomSeries;  // NAME/ folders, replaced (air at -1024 HU)
  nlohmann::json truth;            // truth.json
};

// Creates out and writes the volumes, the DICOM series and truth.json (atomically). On a failure the files this
// call wrote are removed (and out, when it created it), and the error is rethrown.
void writePhantomFiles(const std::filesystem::path& out, const PhantomFiles& files);

} // namespace cementsph::phantom
