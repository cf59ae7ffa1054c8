// `cementsph inject` draws cement_slices.png with what the run knows (issue 20, item 6): the cannula's tip and
// shaft from the scene, each leak in the colour of the class metrics.json gives it, and with --labels the target
// vertebra's outline. The vertebra phantom, a transpedicular tip and 4 ml: a small leak into the canal. The
// colours are CementSlices.h's; what must be there comes from the run's own metrics.json and the label map the
// test writes, not from the picture code.
#include "ProgramRun.h"
#include "RenderingTestSupport.h"

#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <itkImageRegionIteratorWithIndex.h>
#include <nlohmann/json.hpp>

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using cementsph::rendering::test::forgetDisplay;
using cementsph::rendering::test::scratchFolder;
using cementsph::testing::runProgram;

namespace {

const fs::path kPhantom = fs::path(CEMENTSPH_TEST_DATA_DIR) / "vertebra-phantom" / "pre.nrrd";
const std::array<double, 3> kTipMm{35.0, 30.0, 22.5}; // truth.json's suggested transpedicular tip

std::vector<std::string> injectArgs(const fs::path& out) {
  return {"inject", "--ct", kPhantom.string(), "--scene", (fs::path(CEMENTSPH_TEST_DATA_DIR) / "scenes" / "paper-1ml.json").string(),
          "--tip-mm", "35,30,22.5", "--set", "direction=[-0.3,-0.954,0]", "--volume-ml", "4", "--threads", "1",
          "--quiet", "--out", out.string()};
}

// How many pixels of each colour a PNG holds.
std::map<std::array<int, 3>, int> colourCounts(const fs::path& png) {
  std::map<std::array<int, 3>, int> counts;
  for (const auto& rgb : cementsph::rendering::test::readPicture(png).pixels) ++counts[rgb];
  return counts;
}

// CementSlices.h's leak colours by site class.
std::array<int, 3> leakColour(const std::string& kind) {
  static const std::map<std::string, std::array<int, 3>> colours = {
      {"disc", {220, 0, 220}}, {"canal", {255, 140, 0}}, {"venous", {140, 70, 255}}, {"other_bone", {150, 90, 30}}};
  const auto found = colours.find(kind);
  return found == colours.end() ? std::array<int, 3>{230, 20, 20} : found->second;
}

void expectTipShaftAndLeaks(const fs::path& out) {
  const auto counts = colourCounts(out / "cement_slices.png");
  auto count = [&](std::array<int, 3> c) {
    const auto found = counts.find(c);
    return found == counts.end() ? 0 : found->second;
  };
  // Three tip rings (radius 6 px, 2 px thick: pi (7^2 - 5^2) = 75 px each) and the legend's small one.
  EXPECT_GE(count({255, 255, 0}), 3 * 70) << "tip rings missing";
  EXPECT_GE(count({0, 220, 255}), 20) << "no shaft drawn";
  std::ifstream in(out / "metrics.json");
  const nlohmann::json m = nlohmann::json::parse(in);
  ASSERT_TRUE(m.contains("leakage_sites"));
  // The slices cross at the largest site, so its class's colour is on them (and in the legend).
  const nlohmann::json* largest = nullptr;
  for (const auto& site : m["leakage_sites"])
    if (!largest || site["volume_ml"].get<double>() > (*largest)["volume_ml"].get<double>()) largest = &site;
  if (largest) {
    const std::string kind = (*largest)["site_class"].get<std::string>();
    std::cout << "largest leak: " << kind << ", " << (*largest)["volume_ml"].get<double>() << " ml\n";
    EXPECT_GE(count(leakColour(kind)), 20) << "no pixels in the colour of the largest leak's class " << kind;
  }
}

} // namespace

TEST(InjectSlices, TipShaftAndLeakClassesFromTheRun) {
  forgetDisplay();
  const fs::path out = scratchFolder() / "out";
  const auto r = runProgram(CEMENTSPH_EXECUTABLE, injectArgs(out));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  expectTipShaftAndLeaks(out);
  // Without a label map the vertebra is the bone rule's (the run's anatomy_labels.nrrd), outlined all the same
  // (issue 20 item 6; AnatomyLabelsTest checks that map against the phantom's analytic body).
  const auto counts = colourCounts(out / "cement_slices.png");
  ASSERT_EQ(counts.count({0, 200, 80}), 1u);
  EXPECT_GE(counts.at({0, 200, 80}), 300);
}

TEST(InjectSlices, WithALabelMapTheTargetVertebraIsOutlined) {
  forgetDisplay();
  const fs::path dir = scratchFolder();
  // A label map on the phantom's grid: label 26 (a vertebra in TotalSegmentator's numbering) within 20 mm of the
  // tip in x and y and 12 mm in z, a box around the vertebral body; 0 elsewhere.
  const auto ct = cementsph::imaging::readVolume(kPhantom.string());
  auto labels = cementsph::imaging::ImageType::New();
  labels->CopyInformation(ct);
  labels->SetRegions(ct->GetLargestPossibleRegion());
  labels->Allocate();
  labels->FillBuffer(0.0f);
  itk::ImageRegionIteratorWithIndex<cementsph::imaging::ImageType> it(labels, labels->GetLargestPossibleRegion());
  std::size_t inside = 0;
  for (it.GoToBegin(); !it.IsAtEnd(); ++it) {
    itk::Point<double, 3> p;
    labels->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    if (std::abs(p[0] - kTipMm[0]) <= 20 && std::abs(p[1] - kTipMm[1]) <= 20 && std::abs(p[2] - kTipMm[2]) <= 12) {
      it.Set(26.0f);
      ++inside;
    }
  }
  ASSERT_GT(inside, 0u);
  cementsph::imaging::writeVolume(labels, (dir / "labels.nrrd").string());
  std::vector<std::string> args = injectArgs(dir / "out");
  args.insert(args.end(), {"--labels", (dir / "labels.nrrd").string()});
  const auto r = runProgram(CEMENTSPH_EXECUTABLE, args);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  expectTipShaftAndLeaks(dir / "out");
  // The box's outline (2 px inside its boundary) on every panel: at least its 4 sides' length on the smallest.
  const auto counts = colourCounts(dir / "out" / "cement_slices.png");
  const auto green = counts.find({0, 200, 80});
  ASSERT_NE(green, counts.end()) << "no vertebra outline";
  EXPECT_GT(green->second, 3 * 100);
}
