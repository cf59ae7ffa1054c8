// The clinical vertebra phantom (`cementsph phantom --kind vertebra`, VertebraPhantom.h) and its injection:
//  * regression (VertebraPhantomRegression): Data/vertebra-phantom is made again by the command its truth.json
//    records: pre.nrrd voxel for voxel (regenerate after an intended change, from the source folder:
//    build/bin/$(python3 -c 'import json; print(json.load(open("Data/vertebra-phantom/truth.json"))["command"])'));
//    the two tests below are its oracles;
//  * the geometry is where the header says: trabecular bone at the body's centre (90 HU +- 4 sigma of the
//    10 HU noise), cortex in the side wall (partial volume worked out below), CSF in the canal; the DICOM series reads back as the NRRD (to the 1 HU of int16 storage);
//  * the plan of its truth.json with the continuum bone model: an intact posterior wall leaks nothing, the
//    3 mm basivertebral foramen leaks, and every leak site lies within 4 mm of the foramen (its opening and
//    the canal behind it);
//  * 4 ml is held (cement volume within 1 %);
//  * the suggested trajectory is transpedicular: its shaft, from the tip back to the field's edge, keeps the wall of
//    an 11 G cannula (outer diameter 3.05 mm, the gauge table's) out of the canal (distance from the canal's axis,
//    from truth.json's geometry, in the test).
#include "ProgramRun.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace {
nlohmann::json readJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}
fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / name;
  fs::remove_all(p);
  return p;
}
const fs::path kData = fs::path(CEMENTSPH_TEST_DATA_DIR) / "vertebra-phantom";

float at(const cementsph::imaging::ImageType* img, double x, double y, double z) {
  cementsph::imaging::ImageType::PointType p;
  p[0] = x;
  p[1] = y;
  p[2] = z;
  cementsph::imaging::ImageType::IndexType i;
  EXPECT_TRUE(img->TransformPhysicalPointToIndex(p, i));
  return img->GetPixel(i);
}

nlohmann::json inject(const fs::path& ct, const nlohmann::json& plan, const fs::path& out) {
  const nlohmann::json& d = plan.at("direction");
  const auto r = cementsph::testing::runProgram(
      CEMENTSPH_EXECUTABLE,
      {"inject", "--ct", ct.string(), "--scene", (fs::path(CEMENTSPH_TEST_DATA_DIR) / "scenes" / "paper.json").string(),
       "--tip-mm",
       std::to_string(plan["tip_mm"][0].get<double>()) + "," + std::to_string(plan["tip_mm"][1].get<double>()) + "," +
           std::to_string(plan["tip_mm"][2].get<double>()),
       "--set", "direction=" + d.dump(), "--volume-ml", "4", "--quiet", "--no-pictures", "--out", out.string()});
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return readJson(out / "metrics.json");
}
} // namespace

TEST(VertebraPhantomRegression, TheRecordedCommandRemakesTheBundledOne) {
  const nlohmann::json truth = readJson(kData / "truth.json");
  std::string command = truth.at("command").get<std::string>();
  const fs::path out = scratch("vertebra-again");
  const std::string from = "--out " + std::string("Data/vertebra-phantom");
  ASSERT_NE(command.find(from), std::string::npos) << command;
  command.replace(command.find(from), from.size(), "--out " + out.string());
  const auto r = cementsph::testing::runProgram(CEMENTSPH_EXECUTABLE, command.substr(std::string("cementsph ").size()));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto a = cementsph::imaging::readVolume((kData / "pre.nrrd").string());
  const auto b = cementsph::imaging::readVolume((out / "pre.nrrd").string());
  const std::size_t n = a->GetLargestPossibleRegion().GetNumberOfPixels();
  ASSERT_EQ(n, b->GetLargestPossibleRegion().GetNumberOfPixels());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < n; ++i) differing += a->GetBufferPointer()[i] != b->GetBufferPointer()[i];
  EXPECT_EQ(differing, 0u);
}

TEST(VertebraPhantom, TheGeometryIsWhereTheHeaderSaysAndTheDicomSeriesIsTheSameCT) {
  const nlohmann::json v = readJson(kData / "truth.json").at("vertebra");
  const auto ct = cementsph::imaging::readVolume((kData / "pre.nrrd").string());
  const double cx = v["body_centre_mm"][0], cy = v["body_centre_mm"][1], cz = v["body_centre_mm"][2];
  EXPECT_NEAR(at(ct, cx, cy, cz), 90.0, 40.0);                   // trabecular centre, noise 10 HU
  // The side wall: the cortex is the outer 1 mm of wall depth, x in [cx + 18.67, cx + 20] on the centre row
  // (wall depth (1 - x/20) 15 mm < 1 mm); the voxel centred at cx + 19 (x in [18.5, 19.5]) is at least two
  // thirds cortex by the 3 sub-samples per axis: over 2/3 700 + 1/3 20 = 473 HU less 4 sigma of noise.
  EXPECT_GT(at(ct, cx + 19, cy, cz), 473.0 - 40.0);
  EXPECT_LT(at(ct, cx + 21, cy, cz), 20.0 + 40.0); // soft tissue beyond
  EXPECT_NEAR(at(ct, v["canal_centre_mm"][0], v["canal_centre_mm"][1], v["canal_centre_mm"][2]), 10.0, 40.0); // CSF
  const auto dicom = cementsph::imaging::readVolume((kData / "pre_dicom").string());
  const std::size_t n = ct->GetLargestPossibleRegion().GetNumberOfPixels();
  ASSERT_EQ(n, dicom->GetLargestPossibleRegion().GetNumberOfPixels());
  double worst = 0;
  for (std::size_t i = 0; i < n; ++i)
    worst = std::max(worst, double(std::abs(ct->GetBufferPointer()[i] - dicom->GetBufferPointer()[i])));
  EXPECT_LE(worst, 1.0);
  for (unsigned a = 0; a < 3; ++a) EXPECT_NEAR(ct->GetOrigin()[a], dicom->GetOrigin()[a], 1e-3);
}

TEST(VertebraPhantom, AnIntactWallHoldsTheCementAndTheForamenLeaksAtItself) {
  const nlohmann::json truth = readJson(kData / "truth.json");
  const nlohmann::json& plan = truth.at("injection");
  const fs::path intactDir = scratch("vertebra-intact");
  const auto made = cementsph::testing::runProgram(
      CEMENTSPH_EXECUTABLE, {"phantom", "--kind", "vertebra", "--foramen-diameter-mm", "0", "--out", intactDir.string()});
  ASSERT_EQ(made.exitCode, 0) << made.err;
  const nlohmann::json intact = inject(intactDir / "pre.nrrd", plan, scratch("vertebra-intact-inject"));
  EXPECT_EQ(intact.at("bone_model"), "continuum");
  EXPECT_DOUBLE_EQ(intact.at("leakage_volume_ml").get<double>(), 0.0);
  EXPECT_NEAR(intact.at("cement_volume_ml").get<double>(), 4.0, 0.04);
  const nlohmann::json open = inject(kData / "pre.nrrd", plan, scratch("vertebra-open-inject"));
  ASSERT_GT(open.at("leakage_volume_ml").get<double>(), 0.0);
  const auto& f = truth.at("vertebra").at("foramen_mm");
  for (const auto& site : open.at("leakage_sites")) {
    const double dx = site["position_mm"][0].get<double>() - f[0].get<double>();
    const double dy = site["position_mm"][1].get<double>() - f[1].get<double>();
    const double dz = site["position_mm"][2].get<double>() - f[2].get<double>();
    EXPECT_LT(std::sqrt(dx * dx + dy * dy + dz * dz), 4.0) << site.dump();
  }
  EXPECT_NEAR(open.at("cement_volume_ml").get<double>(), 4.0, 0.04);
}

TEST(VertebraPhantom, TheSuggestedShaftPassesBesideTheCanalNotThroughIt) {
  const nlohmann::json truth = readJson(kData / "truth.json");
  const auto& plan = truth.at("injection");
  const auto& v = truth.at("vertebra");
  const double canalX = v["canal_centre_mm"][0], canalY = v["canal_centre_mm"][1], radius = v["canal_radius_mm"];
  const double tipX = plan["tip_mm"][0], tipY = plan["tip_mm"][1];
  const double dx = plan["direction"][0], dy = plan["direction"][1];
  const double fieldY = v["field_mm"][1];
  double closest = 1e9;
  for (double t = 0; tipY - t * dy <= fieldY; t += 0.25) // the shaft runs back from the tip, against the direction
    closest = std::min(closest, std::hypot(tipX - t * dx - canalX, tipY - t * dy - canalY));
  std::cout << "shaft's closest approach to the canal's axis " << closest << " mm (canal radius " << radius << " mm)\n";
  const double cannulaOuterRadiusMm = 0.5 * 3.048; // 11 G
  EXPECT_GT(closest, radius + cannulaOuterRadiusMm);
}
