// What the pictures call a post-injection scan (issue 22 item 3): the label comes from the data's provenance,
// the truth.json that `cementsph phantom` writes beside its scans ("command": the phantom's command line).
// Oracles: the bundled phantoms (made by `cementsph phantom`, their truth.json says so) and folders made here
// with and without such a record.
#include "cementsph/study/ScanProvenance.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace cementsph::study;

namespace {

const fs::path kData = CEMENTSPH_TEST_DATA_DIR;

fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

} // namespace

TEST(ScanProvenance, ThePhantomsPostScanIsLabelledSimulated) {
  EXPECT_TRUE(madeByPhantom(kData / "foam-phantom" / "post.nrrd"));
  EXPECT_EQ(postScanLabel(kData / "foam-phantom" / "post.nrrd"), "post (phantom, simulated)");
  // A DICOM folder: the vertebra phantom's record lies in the folder above its series.
  EXPECT_EQ(postScanLabel(kData / "vertebra-phantom" / "pre_dicom"), "post (phantom, simulated)");
  EXPECT_EQ(postScanLabel((kData / "vertebra-phantom" / "pre_dicom").string() + "/"), "post (phantom, simulated)");
}

TEST(ScanProvenance, AUsersScanIsLabelledCT) {
  const fs::path dir = scratch("scan-provenance");
  fs::create_directories(dir / "plain");
  std::ofstream(dir / "plain" / "post.nrrd") << "not read";
  EXPECT_FALSE(madeByPhantom(dir / "plain" / "post.nrrd"));
  EXPECT_EQ(postScanLabel(dir / "plain" / "post.nrrd"), "post (CT)");

  // A truth.json made by something else, or not JSON, or without a command: not the phantom's record.
  fs::create_directories(dir / "other");
  std::ofstream(dir / "other" / "truth.json") << R"({"command": "my-scanner --export"})";
  EXPECT_EQ(postScanLabel(dir / "other" / "post.nrrd"), "post (CT)");
  fs::create_directories(dir / "garbage");
  std::ofstream(dir / "garbage" / "truth.json") << "{ not json";
  EXPECT_EQ(postScanLabel(dir / "garbage" / "post.nrrd"), "post (CT)");
  fs::create_directories(dir / "nocommand");
  std::ofstream(dir / "nocommand" / "truth.json") << R"({"foam": {}})";
  EXPECT_EQ(postScanLabel(dir / "nocommand" / "post.nrrd"), "post (CT)");

  // The same record written by the phantom: simulated.
  fs::create_directories(dir / "made");
  std::ofstream(dir / "made" / "truth.json") << R"({"command": "cementsph phantom --out made --seed 3"})";
  EXPECT_EQ(postScanLabel(dir / "made" / "post.nrrd"), "post (phantom, simulated)");
}

TEST(ScanProvenance, AReferenceSequenceIsSimulatedWhenAnyOfItsScansIs) {
  const fs::path dir = scratch("scan-provenance-reference");
  const std::string user = (dir / "registered_post.nrrd").string();
  EXPECT_EQ(referenceScansLabel({user}), "reference (CT)");
  EXPECT_EQ(referenceScansLabel({(kData / "foam-phantom" / "pre.nrrd").string(), user}),
            "reference (phantom, simulated)");
  EXPECT_EQ(referenceScansLabel({}), "reference (CT)");
}
