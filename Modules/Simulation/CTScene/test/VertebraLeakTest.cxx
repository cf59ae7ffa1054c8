// Leakage a surgeon can trust (issue "A patient's vertebra", items 1 and 7): the voxel engine on the vertebra
// phantom's anatomy variant (marrow fat inside the body, discs above and below, a basivertebral vein), with the
// tissue classes of Modules/Simulation/Anatomy. The oracle is the phantom's documented geometry (VertebraPhantom.h:
// the body's centre at (field_x / 2, 21, field_z / 2), semi-axes 20 x 15 mm, half height 12.5 mm; fat 7 mm left,
// 3 mm anterior, 2 mm superior of it; discs 10 mm high above and below), written out here, and conservation of the
// injected volume; never a figure of an earlier run.
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/phantom/VertebraPhantom.h"
#include "VertebraVariant.h"
#include "cementsph/scene/InjectionRunner.h"

#include <gtest/gtest.h>
#include <itkImageRegionIteratorWithIndex.h>

#include <cmath>
#include <filesystem>
#include <string>

using namespace cementsph;
using nlohmann::json;

namespace {

struct Variant {
  phantom::VertebraResult phantom;
  std::array<double, 3> centre, fat, disc, canal;
  Variant() {
    const phantom::VertebraOptions o = cementsph::testing::vertebraAnatomyVariant();
    phantom = phantom::makeVertebra(o);
    centre = {o.fieldMm[0] / 2, 21, o.fieldMm[2] / 2};
    fat = {centre[0] + 7, centre[1] - 3, centre[2] + 2};
    disc = {centre[0], centre[1], centre[2] + 12.5 + 5};      // the middle of the upper disc
    canal = {centre[0], centre[1] + 15 + 8, centre[2]};       // the canal's axis
  }
};

const Variant& variant() {
  static const Variant v;
  return v;
}

// A transpedicular-like approach from behind (direction anterior: -y in LPS), bone as a continuum from HU.
scene::SceneConfig sceneAt(const std::array<double, 3>& tip, double volumeMl, bool allowOutsideBone = false) {
  return scene::sceneFromJson({{"tip_mm", tip},
                               {"direction", {0, -1, 0}},
                               {"volume_ml", volumeMl},
                               {"flow_rate_ml_per_s", 0.05},
                               {"viscosity_pa_s", 100},
                               {"cannula_length_mm", 10},
                               {"bone_model", "continuum"},
                               {"allow_tip_outside_bone", allowOutsideBone},
                               {"snapshot_interval_s", 1000}});
}

} // namespace

// Marrow fat (-30 HU, below soft_tissue_max_hu) enclosed by the body is bone, not a leak path: 0.2 ml injected
// at the fat's centre (a ball of about 3.6 mm at full porosity, inside the 5 mm fat sphere, itself 3 mm inside
// the body's trabecular bone) leaks nothing, although most of it sits in voxels below 40 HU.
TEST(VertebraLeak, MarrowFatInsideTheBodyIsNotALeak) {
  const auto r = scene::runInjection(variant().phantom.ct, sceneAt(variant().fat, 0.2), {});
  const auto& m = r.metrics;
  EXPECT_EQ(m.at("leak_rule").get<std::string>().rfind("anatomy", 0), 0u) << m.at("leak_rule");
  EXPECT_NEAR(m.at("cement_volume_ml").get<double>(), 0.2, 0.002);
  EXPECT_EQ(m.at("leakage_volume_ml").get<double>(), 0.0) << m.at("leakage_sites").dump();
  EXPECT_TRUE(m.at("leakage_sites").empty());
}

// A tip outside the vertebra's bone is refused with one line naming the tissue, unless the scene says the
// injection there is deliberate.
TEST(VertebraLeak, TipsOutsideBoneAreRefusedNamingTheTissue) {
  for (const auto& [tip, words] : std::vector<std::pair<std::array<double, 3>, std::string>>{
           {variant().disc, "intervertebral disc"}, {variant().canal, "canal"}}) {
    try {
      scene::runInjection(variant().phantom.ct, sceneAt(tip, 0.05), {});
      ADD_FAILURE() << "no refusal for a tip in the " << words;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(words), std::string::npos) << what;
      EXPECT_NE(what.find("allow_tip_outside_bone"), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

// Cement put into the disc on purpose (allow_tip_outside_bone) is all leakage, reported as a disc site: the disc
// lies between two closed end plates, so the leak's volume is the injected volume (within 1 %).
TEST(VertebraLeak, CementInTheDiscIsADiscLeakOfItsWholeVolume) {
  const auto r = scene::runInjection(variant().phantom.ct, sceneAt(variant().disc, 0.1, true), {});
  const auto& m = r.metrics;
  EXPECT_NEAR(m.at("leakage_volume_ml").get<double>(), m.at("volume_injected_ml").get<double>(), 0.001);
  ASSERT_FALSE(m.at("leakage_sites").empty());
  for (const auto& site : m.at("leakage_sites")) EXPECT_EQ(site.at("site_class"), "disc") << site.dump();
  EXPECT_NEAR(m.at("leakage_by_class").at("volume_ml_by_kind").at("disc").get<double>(), 0.1, 0.001)
      << m.at("leakage_by_class").dump();
}

// A cannula whose shaft runs through the disc (straight down from above the body: direction -z, tip 5 mm below
// the upper end plate, cannula 30 mm long, so 5-15 mm behind the tip lie in the 10 mm disc) is one warning naming
// the disc; the posterior approach of the tests above gives none.
TEST(VertebraLeak, AShaftThroughTheDiscIsAWarning) {
  auto scene = sceneAt({variant().centre[0], variant().centre[1], variant().centre[2] + 12.5 - 5}, 0.05);
  scene.direction = Eigen::Vector3d(0, 0, -1);
  scene.cannulaLengthMm = 30;
  const auto r = scene::runInjection(variant().phantom.ct, scene, {});
  ASSERT_EQ(r.summary.warnings.size(), 1u) << r.metrics.at("warnings").dump();
  EXPECT_NE(r.summary.warnings[0].find("intervertebral disc"), std::string::npos) << r.summary.warnings[0];
  const auto fromBehind = scene::runInjection(variant().phantom.ct, sceneAt(variant().fat, 0.05), {});
  EXPECT_TRUE(fromBehind.summary.warnings.empty()) << fromBehind.metrics.at("warnings").dump();
}

// With a label map (labels_path, label_table), the classes come from the labels, not the CT bone rule: the body
// labelled as vertebra 31 and the disc spaces as 200 from the phantom's analytic geometry (the layout above),
// written as a NRRD on the CT's grid. A tip in the disc is refused naming it; 0.2 ml at the fat's centre (inside
// the labelled body) leaks nothing; and a label map on another grid is one line naming the file.
TEST(VertebraLeak, ALabelMapGivesTheClasses) {
  const auto& v = variant();
  auto labels = imaging::ImageType::New();
  labels->CopyInformation(v.phantom.ct);
  labels->SetRegions(v.phantom.ct->GetLargestPossibleRegion());
  labels->Allocate();
  itk::ImageRegionIteratorWithIndex<imaging::ImageType> it(labels, labels->GetLargestPossibleRegion());
  for (; !it.IsAtEnd(); ++it) {
    imaging::ImageType::PointType p;
    labels->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    const double radial = std::hypot((p[0] - v.centre[0]) / 20, (p[1] - v.centre[1]) / 15);
    const double dz = p[2] - v.centre[2];
    float label = 0;
    if (radial <= 1 && std::abs(dz) <= 12.5) label = 31;
    else if (radial <= 1 && std::abs(dz) > 12.5 && std::abs(dz) <= 22.5) label = 200;
    it.Set(label);
  }
  const std::filesystem::path dir = std::filesystem::path(CEMENTSPH_BINARY_DIR) / "Testing" / "vertebra-labels";
  std::filesystem::create_directories(dir);
  imaging::writeVolume(labels, (dir / "labels.nrrd").string());
  const json table = {{"vertebrae", {31}}, {"disc", {200}}};

  auto withLabels = [&](scene::SceneConfig s) {
    s.labelsPath = (dir / "labels.nrrd").string();
    s.labelTable = table;
    return s;
  };
  try {
    scene::runInjection(v.phantom.ct, withLabels(sceneAt(v.disc, 0.05)), {});
    ADD_FAILURE() << "no refusal for a tip in the labelled disc";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("intervertebral disc"), std::string::npos) << e.what();
  }
  const auto r = scene::runInjection(v.phantom.ct, withLabels(sceneAt(v.fat, 0.2)), {});
  EXPECT_NE(r.metrics.at("leak_rule").get<std::string>().find("labels"), std::string::npos) << r.metrics.at("leak_rule");
  EXPECT_EQ(r.metrics.at("leakage_volume_ml").get<double>(), 0.0) << r.metrics.at("leakage_sites").dump();

  // On another grid: one line naming the file.
  auto shifted = imaging::ImageType::New();
  shifted->CopyInformation(labels);
  auto origin = labels->GetOrigin();
  origin[0] += 1.0;
  shifted->SetOrigin(origin);
  shifted->SetRegions(labels->GetLargestPossibleRegion());
  shifted->Allocate();
  shifted->FillBuffer(0);
  imaging::writeVolume(shifted, (dir / "shifted.nrrd").string());
  auto s = sceneAt(v.fat, 0.05);
  s.labelsPath = (dir / "shifted.nrrd").string();
  try {
    scene::runInjection(v.phantom.ct, s, {});
    ADD_FAILURE() << "a label map on another grid was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("shifted.nrrd"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not on the CT's grid"), std::string::npos) << e.what();
  }
}
