// The synthetic foam phantom (Modules/Simulation/Phantom): porosity, determinism, partial volume, the
// misalignment, the tip in a pore, bad input.
#include "cementsph/phantom/FoamPhantom.h"
#include "cementsph/phantom/PhantomFiles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <stdexcept>
#include <string>

using namespace cementsph::phantom;

namespace {

FoamOptions smallBlock(double porosity) {
  FoamOptions o;
  o.sizeMm = {12, 12, 12};
  o.cellSizeMm = 3.0;
  o.porosity = porosity;
  o.shellMm = 0;
  o.airMarginMm = 0;
  o.noiseHu = 0;
  o.seed = 7;
  return o;
}

std::size_t voxels(const cementsph::imaging::ImageType* image) {
  return image->GetLargestPossibleRegion().GetNumberOfPixels();
}

} // namespace

TEST(FoamPhantom, RealisedPorosityIsWithinThreeHundredthsOfTheTarget) {
  for (double target : {0.6, 0.8, 0.9}) {
    const FoamResult r = makeFoam(smallBlock(target));
    EXPECT_NEAR(r.realisedPorosity, target, 0.03) << "target " << target;
    EXPECT_GT(r.bandMm, 0.0);
    // The voxel mean over the block's voxels (those wholly inside the block's faces) agrees:
    // porosity = (strut - mean HU) / (strut - fat).
    const auto n = r.clean->GetLargestPossibleRegion().GetSize();
    auto inBlock = [&](unsigned a, long i) {
      const double c = r.clean->GetOrigin()[a] + static_cast<double>(i) * r.clean->GetSpacing()[a];
      const double h = 0.5 * r.clean->GetSpacing()[a];
      return c - h >= r.blockMinMm[a] - 1e-9 && c + h <= r.blockMaxMm[a] + 1e-9;
    };
    double sum = 0;
    std::size_t count = 0;
    for (long k = 0; k < static_cast<long>(n[2]); ++k)
      for (long j = 0; j < static_cast<long>(n[1]); ++j)
        for (long i = 0; i < static_cast<long>(n[0]); ++i)
          if (inBlock(0, i) && inBlock(1, j) && inBlock(2, k)) {
            sum += r.clean->GetPixel({{i, j, k}});
            ++count;
          }
    ASSERT_EQ(count, r.blockVoxels);
    const double mean = sum / static_cast<double>(count);
    EXPECT_NEAR((600.0 - mean) / 700.0, r.realisedPorosity, 1e-6);
  }
}

TEST(FoamPhantom, AFixedStrutBandGivesMoreStrutWhenThicker) {
  FoamOptions o = smallBlock(0.8);
  o.porosity.reset();
  o.strutThicknessMm = 0.3;
  const double thin = makeFoam(o).realisedPorosity;
  o.strutThicknessMm = 0.8;
  const double thick = makeFoam(o).realisedPorosity;
  EXPECT_GT(thin, thick);
  EXPECT_LT(thin, 1.0);
}

TEST(FoamPhantom, SameSeedGivesAnIdenticalVolumeAndAnotherSeedDoesNot) {
  FoamOptions o = smallBlock(0.8);
  o.noiseHu = 20;
  o.shellMm = 2;
  const FoamResult a = makeFoam(o), b = makeFoam(o);
  ASSERT_EQ(voxels(a.ct), voxels(b.ct));
  for (std::size_t i = 0; i < voxels(a.ct); ++i) ASSERT_EQ(a.ct->GetBufferPointer()[i], b.ct->GetBufferPointer()[i]);
  o.seed = 8;
  const FoamResult c = makeFoam(o);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < voxels(a.ct); ++i) differ += a.ct->GetBufferPointer()[i] != c.ct->GetBufferPointer()[i];
  EXPECT_GT(differ, voxels(a.ct) / 2);
}

TEST(FoamPhantom, PartialVolumeGivesIntermediateValues) {
  // Struts: voxels partly inside have values strictly between fat and strut.
  const FoamResult r = makeFoam(smallBlock(0.8));
  std::size_t mixed = 0, fat = 0, strut = 0;
  const float* v = r.clean->GetBufferPointer();
  for (std::size_t i = 0; i < voxels(r.clean); ++i) {
    if (v[i] <= -100.0f + 1e-3f) ++fat;
    else if (v[i] >= 600.0f - 1e-3f) ++strut;
    else ++mixed;
  }
  EXPECT_GT(fat, 0u);
  EXPECT_GT(mixed, voxels(r.clean) / 20);
  // A voxel exactly half in the shell (1 mm voxels, 0.5 mm shell, even supersampling) and no strut contrast:
  // the mean of fat (-100) and shell (+120).
  FoamOptions o = smallBlock(0.8);
  o.spacingMm = {1, 1, 1};
  o.sizeMm = {10, 10, 10};
  o.shellMm = 0.5;
  o.supersample = 2;
  o.strutHu = -100;
  const FoamResult h = makeFoam(o);
  ASSERT_EQ(h.ct->GetLargestPossibleRegion().GetSize()[0], 11u);
  EXPECT_NEAR(h.clean->GetPixel({{0, 5, 5}}), 10.0f, 1e-4);   // half shell
  EXPECT_NEAR(h.clean->GetPixel({{0, 0, 5}}), 65.0f, 1e-4);   // a quarter block (corner edge)
  EXPECT_NEAR(h.clean->GetPixel({{5, 5, 5}}), -100.0f, 1e-4); // inside
}

TEST(FoamPhantom, NoiseHasTheRequestedSigma) {
  FoamOptions o = smallBlock(0.8);
  o.noiseHu = 30;
  const FoamResult r = makeFoam(o);
  double s = 0, s2 = 0;
  const std::size_t n = voxels(r.ct);
  for (std::size_t i = 0; i < n; ++i) {
    const double d = r.ct->GetBufferPointer()[i] - r.clean->GetBufferPointer()[i];
    s += d;
    s2 += d * d;
  }
  const double mean = s / static_cast<double>(n);
  EXPECT_NEAR(mean, 0.0, 0.5);
  EXPECT_NEAR(std::sqrt(s2 / static_cast<double>(n) - mean * mean), 30.0, 1.0);
}

TEST(FoamPhantom, TheAffineInvertsAndTheIdentityResamplesExactly) {
  AffineParameters a;
  a.centreMm = {10, 11, 12};
  const std::array<double, 3> x{3, -4, 25};
  const auto y = a.apply(x);
  const auto back = a.applyInverse(y);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(back[i], x[i], 1e-12);
  // The rotation part is a rotation: M = R S, columns of M have the scale as their length.
  const auto m = a.matrix();
  for (int j = 0; j < 3; ++j)
    EXPECT_NEAR(std::sqrt(m[j] * m[j] + m[3 + j] * m[3 + j] + m[6 + j] * m[6 + j]), a.scale[j], 1e-12);
  const FoamResult r = makeFoam(smallBlock(0.8));
  AffineParameters id;
  id.rotationDeg = {0, 0, 0};
  id.scale = {1, 1, 1};
  id.translationMm = {0, 0, 0};
  const auto same = misalign(r.clean, id, -1000.0f);
  for (std::size_t i = 0; i < voxels(r.clean); ++i)
    ASSERT_NEAR(same->GetBufferPointer()[i], r.clean->GetBufferPointer()[i], 1e-3);
  // A whole-voxel shift moves the values by one voxel.
  AffineParameters shift = id;
  shift.translationMm = {0.47, 0, 0};
  const auto moved = misalign(r.clean, shift, -1000.0f);
  EXPECT_EQ(moved->GetPixel({{0, 3, 3}}), -1000.0f);
  EXPECT_NEAR(moved->GetPixel({{6, 3, 3}}), r.clean->GetPixel({{5, 3, 3}}), 1e-3);
}

TEST(FoamPhantom, TheTipMovesToTheNearestPurePoreVoxel) {
  const FoamOptions o = smallBlock(0.8);
  const FoamResult r = makeFoam(o);
  const std::array<double, 3> centre{0.5 * (r.blockMinMm[0] + r.blockMaxMm[0]), 0.5 * (r.blockMinMm[1] + r.blockMaxMm[1]),
                                     0.5 * (r.blockMinMm[2] + r.blockMaxMm[2])};
  const auto tip = nearestPoreMm(r, o, centre);
  cementsph::imaging::ImageType::PointType p;
  for (unsigned i = 0; i < 3; ++i) p[i] = tip[i];
  cementsph::imaging::ImageType::IndexType idx;
  ASSERT_TRUE(r.clean->TransformPhysicalPointToIndex(p, idx));
  EXPECT_LE(r.clean->GetPixel(idx), -99.0f);
  const double moved = std::hypot(tip[0] - centre[0], tip[1] - centre[1], tip[2] - centre[2]);
  EXPECT_LT(moved, o.cellSizeMm);
}

TEST(FoamPhantom, BadInputIsOneLineNamingTheOption) {
  auto expectBad = [](const FoamOptions& o, const std::string& word) {
    try {
      o.validate();
      ADD_FAILURE() << "no error for " << word;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    }
  };
  FoamOptions o = smallBlock(1.2);
  expectBad(o, "porosity");
  o = smallBlock(0.8);
  o.cellSizeMm = -1;
  expectBad(o, "cell_size_mm");
  o = smallBlock(0.8);
  o.strutThicknessMm = 0.5;
  expectBad(o, "not both");
  o = smallBlock(0.8);
  o.sizeMm[1] = 0;
  expectBad(o, "size_mm");
  o = smallBlock(0.8);
  o.noiseHu = -1;
  expectBad(o, "noise_hu");
  PostOptions p;
  p.volumeMl = 0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = PostOptions{};
  p.viscosityPaS = -5;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

TEST(PhantomNumerics, TheInjectionSceneSetsEveryNumericChoiceItself) {
  // Every model key on the scene, from the pinned numerics, not from a scene or engine default.
  const PhantomNumerics n;
  const cementsph::scene::SceneConfig sc = phantomInjectionScene(n, {22.325, 21.855, 21.75}, 1.0, 100.0, 0.05);
  EXPECT_EQ(sc.modelPreset, "default");
  ASSERT_TRUE(sc.integrator && sc.dragCoefficient && sc.soundSpeedMPerS && sc.fixedParticleSums &&
              sc.maxDisplacementOverH && sc.neighbourSkinOverH);
  EXPECT_EQ(*sc.integrator, "overdamped");
  EXPECT_EQ(*sc.dragCoefficient, 8.7);
  EXPECT_EQ(*sc.soundSpeedMPerS, 1.0);
  EXPECT_EQ(sc.fixedSumMethod(), cementsph::sph::FixedSumMethod::Exact);
  EXPECT_EQ(*sc.maxDisplacementOverH, 0.05);
  EXPECT_EQ(*sc.neighbourSkinOverH, 0.2);
  EXPECT_EQ(sc.particleRadiusMm, 0.57);
  EXPECT_EQ(sc.solidMassFactor, 8.0);
  EXPECT_EQ(sc.roiSizeMm, 40.0);
  EXPECT_EQ(sc.volumeMl, 1.0);
  EXPECT_EQ(sc.viscosityPaS, 100.0);
  EXPECT_EQ(sc.direction, Eigen::Vector3d::UnitZ());
  // The record holds them all, with units in the keys.
  const nlohmann::json j = toJson(n);
  EXPECT_EQ(j.at("fixed_particle_sums"), "exact");
  EXPECT_EQ(j.at("max_displacement_over_h"), 0.05);
  EXPECT_EQ(j.at("h_over_d"), 1.0);
  EXPECT_EQ(j.at("viscosity_model"), "drag");
}

TEST(PhantomNumerics, APresetThatNoLongerMatchesIsOneClearError) {
  EXPECT_NO_THROW(checkModelPreset(PhantomNumerics{})); // the preset "default" is still the phantom's model
  PhantomNumerics n;
  n.hOverD = 0.5; // as if the preset had changed under the phantom
  try {
    checkModelPreset(n);
    FAIL() << "a mismatching preset was accepted";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("h/d 1 where the phantom's numerics pin 0.5"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
  n = PhantomNumerics{};
  n.viscosityModel = "morris";
  EXPECT_THROW(checkModelPreset(n), std::runtime_error);
}

// truth.json's plan as the demo gets it (readInjectionPlan): a hand-written file read back exactly, a missing key
// named, and the bundled foam phantom's plan equal to the options of the command its truth.json records
// (--volume-ml 1 --viscosity-pa-s 100; the rate, 0.05 ml/s, is the command's default, as FoamPhantom.h's).
TEST(PhantomFiles, TheInjectionPlanIsReadFromTruthJsonAndAMissingKeyIsNamed) {
  const auto dir = std::filesystem::temp_directory_path() / "cementsph-phantom-plan-test";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "truth.json") << R"({"injection": {"tip_mm": [1.5, -2, 30.25], "direction": [0, -1, 0],
    "volume_ml": 4, "flow_rate_ml_per_s": 0.125, "viscosity_pa_s": 250}})";
  const PhantomInjectionPlan plan = readInjectionPlan(dir);
  EXPECT_EQ(plan.tipMm, (std::array<double, 3>{1.5, -2.0, 30.25}));
  ASSERT_TRUE(plan.direction);
  EXPECT_EQ(*plan.direction, (std::array<double, 3>{0.0, -1.0, 0.0}));
  EXPECT_EQ(plan.volumeMl, 4.0);
  EXPECT_EQ(plan.flowRateMlPerS, 0.125);
  EXPECT_EQ(plan.viscosityPaS, 250.0);

  std::ofstream(dir / "truth.json") << R"({"injection": {"tip_mm": [0, 0, 0], "volume_ml": 1, "viscosity_pa_s": 100}})";
  try {
    (void)readInjectionPlan(dir);
    ADD_FAILURE() << "a plan without its rate was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("injection.flow_rate_ml_per_s is missing"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
  EXPECT_THROW((void)readInjectionPlan(dir), std::runtime_error);

  const auto foam = std::filesystem::path(CEMENTSPH_TEST_DATA_DIR) / "foam-phantom";
  std::ifstream in(foam / "truth.json");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::smatch command;
  ASSERT_TRUE(std::regex_search(text, command, std::regex(R"re("command": "([^"]*)")re")));
  const PhantomInjectionPlan bundled = readInjectionPlan(foam);
  EXPECT_NE(command[1].str().find("--volume-ml 1 "), std::string::npos) << command[1];
  EXPECT_EQ(bundled.volumeMl, 1.0);
  EXPECT_NE(command[1].str().find("--viscosity-pa-s 100"), std::string::npos) << command[1];
  EXPECT_EQ(bundled.viscosityPaS, 100.0);
  EXPECT_EQ(bundled.flowRateMlPerS, PostOptions{}.flowRateMlPerS);
}
