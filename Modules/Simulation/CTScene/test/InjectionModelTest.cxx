// The injection-model interface (InjectionModel.h): a new engine is one class and one registration line, and
// the one driver does everything the engines share. A toy engine registered here, at run time, fills the pore
// voxels of the region nearest the tip first, exactly Q t of cement at time t, with an outlet pressure
// p(t) = 1000 Pa/s * t and a constant cannula drop of 50 Pa. Each check is against what the toy's definition
// implies, worked out here by hand (not read back from the code under test): the snapshot times, the volume at
// each snapshot, the pressure figures, the simulated CT's voxels, the metrics keys, and the driver's refusals
// (an unknown name, a non-finite figure, a key the driver owns).
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/provenance/Provenance.h"
#include "cementsph/scene/InjectionModel.h"
#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/sph/Simulation.h"
#include "ScaffoldCT.h"

#include <gtest/gtest.h>
#include <vtkCellArray.h>
#include <vtkPoints.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <sstream>

using namespace cementsph;
using namespace cementsph::scene;
namespace fs = std::filesystem;

namespace {

constexpr double kPressureRatePaPerS = 1000.0, kCannulaPa = 50.0;

// What the toy does when asked to misbehave.
enum class Fault { None, NonFiniteFigure, ClaimsADriverKey };

class ToyBall final : public InjectionModel {
public:
  explicit ToyBall(Fault fault = Fault::None) : fault_(fault) {}

  void start(const InjectionSetup& s) override {
    solid_ = s.solid;
    flow_ = s.scene->flowRateM3PerS();
    rho0_ = s.model.restDensity;
    const Eigen::Vector3d tip = *s.scene->tipMm * 1e-3;
    for (std::size_t c = 0; c < solid_->solid.size(); ++c)
      if (!solid_->solid[c]) order_.push_back(c);
    std::stable_sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) {
      return (centre(a) - tip).squaredNorm() < (centre(b) - tip).squaredNorm();
    });
  }
  double time() const override { return t_; }
  void advance(double dtMax) override { t_ += dtMax; } // exactly to the next snapshot or the end
  TipRecord outlet() const override { return {t_, kPressureRatePaPerS * t_, kCannulaPa}; }
  double injectedVolumeM3() const override { return flow_ * t_; }
  double cementVolumeM3() const override { return flow_ * t_; }
  std::string state() const override { return "toy"; }
  std::vector<double> cementDensity() const override {
    std::vector<double> rho(solid_->grid.count(), 0.0);
    double left = flow_ * t_;
    for (std::size_t c : order_) {
      if (left <= 0) break;
      const double f = std::min(1.0, left / solid_->grid.voxelVolume());
      rho[c] = f * rho0_;
      left -= f * solid_->grid.voxelVolume();
    }
    return rho;
  }
  vtkSmartPointer<vtkPolyData> cement() const override {
    auto poly = vtkSmartPointer<vtkPolyData>::New();
    auto points = vtkSmartPointer<vtkPoints>::New();
    const std::vector<double> rho = cementDensity();
    for (std::size_t c = 0; c < rho.size(); ++c)
      if (rho[c] > 0) {
        const Eigen::Vector3d mm = centre(c) * 1e3;
        points->InsertNextPoint(mm.data());
      }
    poly->SetPoints(points);
    return poly;
  }
  void report(InjectionSummary& s, nlohmann::json& e) const override {
    s.steps = std::size_t(std::lround(t_)); // not a figure the test checks
    e["toy_fills_voxels_nearest_first"] = true;
    s.leakageSites.push_back({{1.0, 2.0, 3.0}, 0.5, 0.001, "disc"}); // a site for the Slicer file to list
    if (fault_ == Fault::NonFiniteFigure) e["toy_figure_pa"] = std::numeric_limits<double>::quiet_NaN();
    if (fault_ == Fault::ClaimsADriverKey) e["cement_volume_ml"] = 0.0;
  }

private:
  Eigen::Vector3d centre(std::size_t c) const {
    const std::size_t nx = std::size_t(solid_->grid.size[0]), ny = std::size_t(solid_->grid.size[1]);
    const Eigen::Vector3d ijk(double(c % nx), double((c / nx) % ny), double(c / (nx * ny)));
    return solid_->grid.origin + ijk.cwiseProduct(solid_->grid.spacing);
  }

  Fault fault_;
  const PorousSolid* solid_ = nullptr;
  double flow_ = 0, rho0_ = 0, t_ = 0;
  std::vector<std::size_t> order_;
};

// The one registration line a new engine needs (here at run time; a built-in one goes in InjectionModels.cpp).
void registerToys() {
  auto& registry = InjectionModelRegistry::instance();
  if (registry.has("toy-ball")) return;
  registry.add("toy-ball", [] { return std::make_unique<ToyBall>(); }, "toy-ball-nearest-pores-first");
  registry.add("toy-nan", [] { return std::make_unique<ToyBall>(Fault::NonFiniteFigure); }, "toy");
  registry.add("toy-greedy", [] { return std::make_unique<ToyBall>(Fault::ClaimsADriverKey); }, "toy");
}

// 0.02 ml at 0.01 ml/s (T = 2 s), a snapshot every 0.5 s.
SceneConfig toyScene(const std::string& engine) {
  SceneConfig scene = sceneFromJson({{"tip_mm", {13, 13, 13}},
                                     {"volume_ml", 0.02},
                                     {"flow_rate_ml_per_s", 0.01},
                                     {"snapshot_interval_s", 0.5},
                                     {"cannula_length_mm", 5}});
  scene.pressureModel = engine;
  return scene;
}

std::vector<double> pvdTimes(const fs::path& pvd) {
  std::ifstream in(pvd);
  std::stringstream text;
  text << in.rdbuf();
  std::vector<double> times;
  const std::string s = text.str(), key = "timestep=\"";
  for (std::size_t at = s.find(key); at != std::string::npos; at = s.find(key, at + 1))
    times.push_back(std::stod(s.substr(at + key.size())));
  return times;
}

} // namespace

TEST(InjectionModel, ARegisteredToyRunsThroughTheOneDriver) {
  registerToys();
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "injection-model-toy";
  fs::remove_all(out);
  InjectionRunOptions o;
  o.outDir = out.string();
  const auto ct = scene::testing::scaffold();
  const InjectionResult r = runInjection(ct, toyScene("toy-ball"), o);
  const auto& m = r.metrics;

  // Chosen by its name, described by its registration.
  EXPECT_EQ(m.at("pressure_model"), "toy-ball");
  EXPECT_EQ(m.at("model"), "toy-ball-nearest-pores-first");
  EXPECT_EQ(m.at("toy_fills_voxels_nearest_first"), true);
  EXPECT_FALSE(m.contains("fluid_particles")); // no particle counts faked for an engine without particles

  // The driver's loop stops at every snapshot: 0.5, 1, 1.5 s and the end, 2 s.
  const std::vector<double> times = pvdTimes(out / "particles.pvd");
  ASSERT_EQ(times.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) EXPECT_NEAR(times[k], 0.5 * double(k + 1), 1e-9);

  // The volume at each snapshot: Q t (0.01 ml/s).
  const auto& history = m.at("volume_history");
  ASSERT_EQ(history.size(), 4u);
  for (const auto& h : history)
    EXPECT_NEAR(h.at("cement_volume_ml").get<double>(), 0.01 * h.at("time_s").get<double>(), 1e-12);
  EXPECT_NEAR(m.at("volume_injected_ml").get<double>(), 0.02, 1e-12);
  EXPECT_NEAR(m.at("simulated_time_s").get<double>(), 2.0, 1e-12);

  // Pressures: p(t) = 1000 t, largest and last at t = 2 s; the syringe adds the cannula's 50 Pa.
  EXPECT_NEAR(m.at("final_tip_pressure_pa").get<double>(), 2000.0, 1e-9);
  EXPECT_NEAR(m.at("max_tip_pressure_pa").get<double>(), 2000.0, 1e-9);
  EXPECT_NEAR(m.at("cannula_pressure_drop_pa").get<double>(), 50.0, 1e-12);
  EXPECT_NEAR(m.at("max_injection_pressure_pa").get<double>(), 2050.0, 1e-9);
  ASSERT_EQ(r.tipSeries.size(), 4u); // one outlet sample per step

  // The simulated CT: the CT's HU plus k = 3000 HU times the filled fraction, in the voxels the toy fills:
  // 0.02 ml over 0.125 mm^3 voxels = 160 voxels, all full.
  // The background: the scaffold's own voxels over the run's region (metrics' roi_start_index, roi_voxels).
  const auto roi = r.simulatedCt;
  const auto size = roi->GetLargestPossibleRegion().GetSize();
  for (unsigned a = 0; a < 3; ++a) ASSERT_EQ(long(size[a]), r.summary.roiSize[a]);
  std::size_t raised = 0;
  double addedHu = 0;
  for (long k = 0; k < long(size[2]); ++k)
    for (long j = 0; j < long(size[1]); ++j)
      for (long i = 0; i < long(size[0]); ++i) {
        const itk::Index<3> at{{i, j, k}}, inCt{{r.summary.roiStart[0] + i, r.summary.roiStart[1] + j, r.summary.roiStart[2] + k}};
        const double d = double(roi->GetPixel(at)) - double(ct->GetPixel(inCt));
        if (d > 0.5) ++raised;
        addedHu += d;
      }
  EXPECT_EQ(raised, 160u);
  EXPECT_NEAR(addedHu, 160 * 3000.0, 1.0);
  EXPECT_TRUE(fs::exists(out / "metrics.json"));
  EXPECT_TRUE(fs::exists(out / "tip_pressure.csv"));

  // 3D Slicer's files: the tip and the trajectory's entry, a cannula length (5 mm) behind it along the scene's
  // direction (0, 0, 1), in LPS mm; the toy's one leak site; the label map's colours.
  std::ifstream markupsFile(out / "injection.mrk.json");
  const auto markups = nlohmann::json::parse(markupsFile);
  EXPECT_NE(markups.at("@schema").get<std::string>().find("markups-schema"), std::string::npos);
  const auto& tip = markups.at("markups").at(0);
  EXPECT_EQ(tip.at("type"), "Fiducial");
  EXPECT_EQ(tip.at("coordinateSystem"), "LPS");
  EXPECT_EQ(tip.at("controlPoints").at(0).at("position"), nlohmann::json::parse("[13.0, 13.0, 13.0]"));
  const auto& line = markups.at("markups").at(1);
  EXPECT_EQ(line.at("type"), "Line");
  EXPECT_EQ(line.at("controlPoints").at(0).at("position"), nlohmann::json::parse("[13.0, 13.0, 8.0]"));
  std::ifstream leaksFile(out / "leak_sites.mrk.json");
  const auto leaks = nlohmann::json::parse(leaksFile).at("markups").at(0).at("controlPoints");
  ASSERT_EQ(leaks.size(), 1u);
  EXPECT_EQ(leaks.at(0).at("position"), nlohmann::json::parse("[1.0, 2.0, 3.0]"));
  EXPECT_NE(leaks.at(0).at("label").get<std::string>().find("disc"), std::string::npos);
  std::ifstream colours(out / "cement_labels.ctbl");
  std::string line1, line2, line3;
  std::getline(colours, line1);
  std::getline(colours, line2), std::getline(colours, line2);
  std::getline(colours, line3);
  EXPECT_EQ(line2.rfind("1 ", 0), 0u) << line2;
  EXPECT_EQ(line3.rfind("2 ", 0), 0u) << line3;
}

TEST(InjectionModel, AnUnknownNameIsOneLineListingTheModels) {
  try {
    runInjection(scene::testing::scaffold(), toyScene("two-phase-marrow"), {});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("pressure_model \"two-phase-marrow\""), std::string::npos) << what;
    for (const char* name : {"\"voxel-darcy\"", "\"incompressible\"", "\"equation-of-state\""})
      EXPECT_NE(what.find(name), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
}

TEST(InjectionModel, ANonFiniteFigureFailsTheRunAndWritesNoMetrics) {
  registerToys();
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "injection-model-nan";
  fs::remove_all(out);
  InjectionRunOptions o;
  o.outDir = out.string();
  try {
    runInjection(scene::testing::scaffold(), toyScene("toy-nan"), o);
    FAIL() << "no error";
  } catch (const sph::SimulationError& e) {
    EXPECT_NE(std::string(e.what()).find("toy_figure_pa"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(out / "metrics.json"));
  EXPECT_FALSE(fs::exists(out / "particles_0000.vtp")); // the failed run's snapshots go with it
}

TEST(InjectionModel, AnEngineCannotOverwriteWhatTheDriverReports) {
  registerToys();
  EXPECT_THROW(runInjection(scene::testing::scaffold(), toyScene("toy-greedy"), {}), std::logic_error);
}

TEST(InjectionModel, TheSummaryCrossesAProcessBoundaryIntact) {
  registerToys();
  const InjectionResult r = runInjection(scene::testing::scaffold(), toyScene("toy-ball"), {});
  const InjectionSummary back = InjectionSummary::fromJson(r.metrics);
  EXPECT_EQ(back.toJson(), r.summary.toJson());
  nlohmann::json broken = r.metrics;
  broken.erase("cement_volume_ml");
  EXPECT_THROW(InjectionSummary::fromJson(broken), std::invalid_argument);
}

// Provenance in every metrics.json: the project's version (CMake's, passed to this test independently), and
// the command line as a shell would need it typed again.
TEST(InjectionModel, MetricsNameTheProgramVersionAndCommandLine) {
  const char* argv[] = {"cementsph", "inject", "--tip-mm", "1, 2, 3", "--set", "note='x'"};
  provenance::setCommandLine(6, argv);
  EXPECT_EQ(provenance::commandLine(), "cementsph inject --tip-mm '1, 2, 3' --set 'note='\\''x'\\'''");
  registerToys();
  const InjectionResult r = runInjection(scene::testing::scaffold(), toyScene("toy-ball"), {});
  const auto& p = r.metrics.at("provenance");
  EXPECT_EQ(p.at("version"), CEMENTSPH_PROJECT_VERSION);
  EXPECT_EQ(p.at("command_line"), provenance::commandLine());
  const std::string revision = p.at("git_revision");
  EXPECT_TRUE(revision == "unknown" || revision.size() >= 12) << revision;
}

// Cement in the region's outermost voxels is a warning: 0.14 ml on the 20 mm scaffold CT with a 6 mm region
// (its pores hold 0.153 ml: the toy, filling the nearest pore voxels first, fills 91 % of them, the faces' too),
// which is not the scan's edge; the same scene in the whole scan stays inside and warns of nothing.
TEST(InjectionModel, CementAtTheRegionsEdgeIsAWarning) {
  registerToys();
  SceneConfig scene = toyScene("toy-ball");
  scene.volumeMl = 0.14;
  scene.flowRateMlPerS = 0.07;
  scene.roiSizeMm = 6;
  const InjectionResult cut = runInjection(scene::testing::scaffold(), scene, {});
  ASSERT_EQ(cut.summary.warnings.size(), 1u) << cut.metrics.at("warnings").dump();
  EXPECT_NE(cut.summary.warnings[0].find("region of interest"), std::string::npos) << cut.summary.warnings[0];
  scene.volumeMl = 0.02;
  scene.flowRateMlPerS = 0.01;
  scene.roiSizeMm = 40;
  EXPECT_TRUE(runInjection(scene::testing::scaffold(), scene, {}).summary.warnings.empty());
}
