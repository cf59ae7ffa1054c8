// The `cementsph compare` and `register` commands, run as a user would: outputs and metrics.json
// keys on a synthetic case; clear messages, non-zero exits and no partial output on bad input;
// an honest zero when there is no cement.
#include "SyntheticVolumes.h"
#include "cementsph/imaging/VolumeIO.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <itkContinuousIndex.h>
#include <itkImageFileWriter.h>
#include <itkImageRegionIteratorWithIndex.h>
#include <itkNrrdImageIO.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>
#include <sys/wait.h>

namespace fs = std::filesystem;
using namespace cementsph::testing;
using cementsph::imaging::writeVolume;

namespace {

struct ProgramRun {
  int exitCode = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

ProgramRun run(const std::string& args, const fs::path& scratch) {
  const std::string cmd = std::string(CEMENTSPH_EXE) + " " + args + " > " + (scratch / "stdout.txt").string() +
                          " 2> " + (scratch / "stderr.txt").string();
  const int status = std::system(cmd.c_str());
  ProgramRun r;
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = slurp(scratch / "stdout.txt");
  r.err = slurp(scratch / "stderr.txt");
  return r;
}

class CompareCommand : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    // One folder per test process: ctest runs each test in its own process, possibly in parallel (-j).
    dir_ = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / ("compare-command-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    CompareCase c;
    c.grid.size = {60, 60, 56};
    c.grid.spacing = {0.7, 0.7, 0.75};
    c.grid.origin = {-20.65, -20.65, -20.625};
    c.semiAxesMm = {17, 15, 16};
    c.seed = 3;
    c.rotationDeg = {2, -3, 4};
    c.translationMm = {1.5, -1.0, 2.0};
    // Post: a 6 mm ball; the "simulation": a slightly larger ball, displaced 1 mm.
    c.cementRadiusMm = 6.0;
    c.simRadiusMm = 6.5;
    c.simOffsetMm = 1.0;
    tip_ = writeCompareCase(c, dir_.string());
    const Grid& grid = c.grid;
    const BonePhantom phantom(gridCentre(grid), c.semiAxesMm, c.seed);
    // Post scanned somewhere else entirely: no overlap with pre.
    Grid far = grid;
    far.origin = {900, 900, 900};
    writeVolume(sample(phantom, far), (dir_ / "far.nrrd").string());
  }

  std::string point() const {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.3f,%.3f,%.3f", tip_[0], tip_[1], tip_[2]);
    return buf;
  }
  std::string common(const std::string& post, const std::string& out) const {
    return "compare --pre " + (dir_ / "pre.nrrd").string() + " --post " + post +
           " --injection-point-mm " + point() + " --out " + (dir_ / out).string();
  }

  static inline fs::path dir_;
  static inline Vec3 tip_{};
};

bool hasTemporaries(const fs::path& dir) {
  if (!fs::exists(dir)) return false;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().find(".tmp-") != std::string::npos) return true;
  return false;
}

} // namespace

TEST_F(CompareCommand, HelpNamesTheUnits) {
  const ProgramRun r = run("compare --help", dir_);
  EXPECT_EQ(r.exitCode, 0);
  EXPECT_NE(r.out.find("--injection-point-mm"), std::string::npos);
  EXPECT_NE(r.out.find("--threshold-hu"), std::string::npos);
}

TEST_F(CompareCommand, WritesMetricsSurfacesAndVolumes) {
  const ProgramRun r = run(common((dir_ / "post.nrrd").string(), "ok") + " --simulated " + (dir_ / "sim.nrrd").string(), dir_);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const fs::path out = dir_ / "ok";
  for (const char* f : {"metrics.json", "registered_post.nrrd", "pre_to_post.tfm", "cement_ct_mask.nrrd",
                        "cement_simulated_mask.nrrd", "cement_ct_surface.vtp", "cement_simulated_surface.vtp"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  EXPECT_FALSE(hasTemporaries(out));
  const auto m = nlohmann::json::parse(slurp(out / "metrics.json"));
  for (const char* key : {"cement_volume_ml", "mean_spreading_distance_mm", "error_mm", "hausdorff_mm",
                          "hausdorff95_mm", "dice", "jaccard", "centroid_offset_mm"})
    ASSERT_TRUE(m.contains(key) && m[key].is_number()) << key;
  for (const char* key : {"ct_to_simulated_distance", "simulated_to_ct_distance"})
    for (const char* sub : {"mean_mm", "max_mm", "std_mm"}) ASSERT_TRUE(m[key][sub].is_number()) << key << sub;
  // The synthetic ball (r = 6 mm, 3000 HU over tissue near 0 HU) has a logistic edge of scale 0.35 mm:
  // half the cement's contrast (w = 1/2) puts the mask's edge at r itself, 0.905 ml. (The old fixed
  // 500 HU, w = 1/6, put it at r + 0.35 ln 5 = 6.56 mm, 1.18 ml: +31 %.)
  const double ballMl = 4.0 / 3.0 * M_PI * 6.0 * 6.0 * 6.0 / 1000.0;
  EXPECT_NEAR(m["cement_volume_ml"].get<double>(), ballMl, 0.03 * ballMl);
  EXPECT_NEAR(m["cement_threshold_hu"].get<double>(), 1500.0, 150.0);
  EXPECT_EQ(m["ct"]["threshold_rule"], "half-contrast");
  // A ball centred 1 mm from the injection point: mean spreading distance ~ 3R/4 = 4.5 mm.
  EXPECT_NEAR(m["mean_spreading_distance_mm"].get<double>(), 4.6, 1.0);
  EXPECT_GT(m["dice"].get<double>(), 0.6);
  EXPECT_LT(m["error_mm"].get<double>(), 2.0);
  EXPECT_GE(m["hausdorff_mm"].get<double>(), m["hausdorff95_mm"].get<double>());
  EXPECT_NEAR(m["centroid_offset_mm"].get<double>(), 1.0, 0.6);
  EXPECT_FALSE(m["registration"]["levels"].empty());
  EXPECT_NE(r.out.find("error (larger mean)"), std::string::npos) << r.out;
}

TEST_F(CompareCommand, RegisterStandsOnItsOwn) {
  const fs::path out = dir_ / "register";
  fs::create_directories(out);
  const ProgramRun r = run("register --fixed " + (dir_ / "pre.nrrd").string() + " --moving " +
                        (dir_ / "post.nrrd").string() + " --out-transform " + (out / "t.tfm").string() +
                        " --out-image " + (out / "r.nrrd").string(),
                    dir_);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / "t.tfm"));
  EXPECT_TRUE(fs::exists(out / "r.nrrd"));
  EXPECT_NE(r.out.find("final metric"), std::string::npos);
}

// The pre scan given as the post scan: no cement to compare, so one line and no output at all.
TEST_F(CompareCommand, NoCementIsOneLineAndNoOutput) {
  const ProgramRun r = run(common((dir_ / "pre.nrrd").string(), "none"), dir_);
  EXPECT_EQ(r.exitCode, 1) << r.err;
  EXPECT_NE(r.err.find("no cement found"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "none"));
}

TEST_F(CompareCommand, BadInputFailsCleanlyWithoutOutput) {
  // Missing file.
  ProgramRun r = run(common((dir_ / "missing.nrrd").string(), "bad1"), dir_);
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.err.find("missing.nrrd: no such file"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad1"));
  // Corrupt file.
  std::ofstream(dir_ / "corrupt.nrrd") << "NRRD0004\ngarbage\n";
  r = run(common((dir_ / "corrupt.nrrd").string(), "bad2"), dir_);
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.err.find("corrupt.nrrd"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad2"));
  // Truncated file.
  fs::copy_file(dir_ / "post.nrrd", dir_ / "truncated.nrrd", fs::copy_options::overwrite_existing);
  fs::resize_file(dir_ / "truncated.nrrd", fs::file_size(dir_ / "truncated.nrrd") / 2);
  r = run(common((dir_ / "truncated.nrrd").string(), "bad3"), dir_);
  EXPECT_NE(r.exitCode, 0);
  EXPECT_FALSE(fs::exists(dir_ / "bad3"));
  // A 2-D image.
  using Image2 = itk::Image<float, 2>;
  auto flat = Image2::New();
  flat->SetRegions(Image2::RegionType({{0, 0}}, {{16, 16}}));
  flat->Allocate();
  flat->FillBuffer(0.0f);
  auto writer = itk::ImageFileWriter<Image2>::New();
  writer->SetImageIO(itk::NrrdImageIO::New());
  writer->SetInput(flat);
  writer->SetFileName((dir_ / "flat.nrrd").string());
  writer->Update();
  r = run(common((dir_ / "flat.nrrd").string(), "bad4"), dir_);
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.err.find("not a 3-D volume"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad4"));
  // Volumes that do not overlap in space.
  r = run(common((dir_ / "far.nrrd").string(), "bad5"), dir_);
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.err.find("do not overlap"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad5"));
  // Missing required option: CLI11's usage error.
  r = run("compare --pre " + (dir_ / "pre.nrrd").string(), dir_);
  EXPECT_NE(r.exitCode, 0);
}

// The README's compare command on the example shipped in Data/compare-example (post as a DICOM
// series, pre and simulated CT as NRRD; made by `make-compare-example`). Oracles from its truth.json:
// two balls, R = 5.5 mm (cement) and 6.0 mm (simulated), centres 0.8 mm apart. Dice of two such balls
// is 0.856 (lens volume, analytic); the mean surface distances lie between R2 - R1 - d = -0.3 and
// R2 - R1 + d = 1.3, centred near 0.5 mm. The 500 HU threshold of the difference image grows each
// segmentation by ~0.5 mm (partial volume of a 3000 HU ball), which lifts Dice slightly: 0.05 allowed.
TEST(CompareCommandExample, ReadmeCommandOnBundledDicomAndNrrd) {
  const fs::path data = fs::path(CEMENTSPH_TEST_DATA_DIR) / "compare-example";
  const auto truth = nlohmann::json::parse(slurp(data / "truth.json"));
  const auto& p = truth["injection_point_mm"];
  char point[96];
  std::snprintf(point, sizeof point, "%.3f,%.3f,%.3f", p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  const fs::path scratch = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "compare-example";
  fs::remove_all(scratch);
  fs::create_directories(scratch);
  const ProgramRun r = run("compare --pre " + (data / "pre.nrrd").string() + " --post " + (data / "post_dicom").string() +
                               " --simulated " + (data / "simulated.nrrd").string() + " --injection-point-mm " + point +
                               " --out " + (scratch / "out").string(),
                           scratch);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto m = nlohmann::json::parse(slurp(scratch / "out" / "metrics.json"));
  EXPECT_NEAR(m["dice"].get<double>(), 0.856, 0.05);
  EXPECT_NEAR(m["error_mm"].get<double>(), 0.5, 0.25);
  // The CT cement ball: 4/3 pi 5.5^3 = 0.697 ml before the threshold's ~0.5 mm growth (0.9 ml at 6 mm).
  EXPECT_GT(m["cement_volume_ml"].get<double>(), 0.697);
  EXPECT_LT(m["cement_volume_ml"].get<double>(), 0.905 * 1.1);
}

TEST(CompareCommandExample, RegisterCreatesItsOutputFolder) {
  const fs::path data = fs::path(CEMENTSPH_TEST_DATA_DIR) / "compare-example";
  const fs::path scratch = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "register-example";
  fs::remove_all(scratch);
  fs::create_directories(scratch);
  const fs::path out = scratch / "not" / "yet";
  const ProgramRun r = run("register --pre " + (data / "pre.nrrd").string() + " --post " + (data / "post_dicom").string() +
                               " --out-transform " + (out / "t.tfm").string() + " --out-image " + (out / "r.nrrd").string(),
                           scratch);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / "t.tfm"));
  EXPECT_TRUE(fs::exists(out / "r.nrrd"));
}

// ---- The bundled example (issue 12, item 4): Data/compare-example, whose truth.json holds the cement
// ball (radius 5.5 mm at the injection point, in the post scan's space) and the misalignment. The perfect
// simulation is the truth itself on the pre grid: sim(x) = post(A x), the ball blended into the pre scan
// exactly as the example's generator blends it (logistic edge, 0.35 mm, 3000 HU). compare must find the
// ball's volume within 2 % and, for the perfect simulation, an error below 0.05 mm.
TEST(CompareExample, VolumeWithin2PercentAndPerfectSimulationErrorBelow005Mm) {
  const fs::path example = fs::path(CEMENTSPH_TEST_DATA_DIR) / "compare-example";
  const auto truth = nlohmann::json::parse(slurp(example / "truth.json"));
  const auto pre = cementsph::imaging::readVolume((example / "pre.nrrd").string());
  const fs::path scratch = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / ("compare-example-" + std::to_string(::getpid()));
  fs::remove_all(scratch);
  fs::create_directories(scratch);

  Vec3 rotation{}, scale{}, translation{}, tip{};
  for (int i = 0; i < 3; ++i) {
    rotation[i] = truth["misalignment_rotation_deg"][i];
    scale[i] = truth["misalignment_scale"][i];
    translation[i] = truth["misalignment_translation_mm"][i];
    tip[i] = truth["injection_point_mm"][i];
  }
  const double radius = truth["cement_radius_mm"];
  const auto size = pre->GetLargestPossibleRegion().GetSize();
  itk::ContinuousIndex<double, 3> middle;
  for (unsigned i = 0; i < 3; ++i) middle[i] = (static_cast<double>(size[i]) - 1.0) / 2.0;
  cementsph::imaging::PointType centrePoint;
  pre->TransformContinuousIndexToPhysicalPoint(middle, centrePoint);
  const Affine move = Affine::fromParameters(rotation, scale, translation, {centrePoint[0], centrePoint[1], centrePoint[2]});
  const Vec3 ballCentre = move.apply(tip);

  auto perfect = cementsph::imaging::ImageType::New();
  perfect->CopyInformation(pre);
  perfect->SetRegions(pre->GetLargestPossibleRegion());
  perfect->Allocate();
  itk::ImageRegionIteratorWithIndex<cementsph::imaging::ImageType> it(perfect, perfect->GetLargestPossibleRegion());
  for (; !it.IsAtEnd(); ++it) {
    cementsph::imaging::PointType x;
    perfect->TransformIndexToPhysicalPoint(it.GetIndex(), x);
    const Vec3 y = move.apply({x[0], x[1], x[2]});
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) d2 += (y[a] - ballCentre[a]) * (y[a] - ballCentre[a]);
    const double w = 1.0 / (1.0 + std::exp((std::sqrt(d2) - radius) / 0.35));
    it.Set(static_cast<float>((1.0 - w) * pre->GetPixel(it.GetIndex()) + w * 3000.0));
  }
  writeVolume(perfect, (scratch / "perfect.nrrd").string());

  char point[96];
  std::snprintf(point, sizeof point, "%.4f,%.4f,%.4f", tip[0], tip[1], tip[2]);
  const ProgramRun r = run("compare --pre " + (example / "pre.nrrd").string() + " --post " +
                               (example / "post_dicom").string() + " --simulated " + (scratch / "perfect.nrrd").string() +
                               " --injection-point-mm " + point + " --no-pictures --out " + (scratch / "out").string(),
                           scratch);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto m = nlohmann::json::parse(slurp(scratch / "out" / "metrics.json"));
  // The ball is drawn in the post scan's space; on the pre grid its volume is divided by det(M), the
  // product of the scales (a rotation keeps volumes).
  const double truthMl = 4.0 / 3.0 * M_PI * radius * radius * radius / 1000.0 / (scale[0] * scale[1] * scale[2]);
  std::cout << "compare-example: CT cement " << m["cement_volume_ml"] << " ml (truth " << truthMl
            << "), threshold " << m["cement_threshold_hu"] << " HU, perfect simulation "
            << m["simulated"]["cement_volume_ml"] << " ml, error " << m["error_mm"] << " mm\n";
  EXPECT_NEAR(m["cement_volume_ml"].get<double>(), truthMl, 0.02 * truthMl);
  EXPECT_NEAR(m["simulated"]["cement_volume_ml"].get<double>(), truthMl, 0.02 * truthMl);
  EXPECT_LT(m["error_mm"].get<double>(), 0.05);
  fs::remove_all(scratch);
}
