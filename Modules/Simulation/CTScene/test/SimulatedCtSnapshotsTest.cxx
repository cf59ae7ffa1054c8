// The scene key simulated_ct_snapshots (issue 5, X-ray sequences): the inject runner writes the simulated CT
// at t = 0 and at every particle snapshot, lists them in sequence.json, and the last one is the final
// simulated_ct.nrrd. Oracles: the t = 0 frame is the input CT's ROI voxel for voxel (no fluid yet); a frame's
// HU is HU_pre + 3000 rho / rho0 with rho = sum m W (Eq. 2, h = 2r) summed here by brute force with the
// cubic spline written out, over that snapshot's particles; the cement a frame holds (its HU rise integrated)
// is the volume the cannula emitted by then, Q t (volume-exact emission); frame times are the snapshots'.
// A known cloud (a cubic lattice) voxelised gives, at a voxel on a lattice site deep inside, the lattice
// sum computed by hand, and holds the cloud's mass.
#include "cementsph/imaging/PolyDataIO.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/PorousSolid.h"
#include "cementsph/scene/SimulatedCT.h"
#include "cementsph/sph/ParticleVoxeliser.h"
#include "cementsph/scene/InjectionRunner.h"
#include "ScaffoldCT.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <vtkPolyData.h>

using namespace cementsph;
using namespace cementsph::scene;
namespace fs = std::filesystem;

namespace {

const int kOneThread = [] {
  omp_set_num_threads(1);
  return 1;
}();

constexpr double kPi = 3.14159265358979323846;
constexpr double kRho0 = 1180.0;          // kg/m^3, the cement's rest density (the model presets)
constexpr double kHuPerRelative = 3000.0; // InjectionRunOptions' default k
constexpr double kD = 1.14e-3;            // m: d = 2r at the scene's r = 0.57 mm; the simulated CT's h = 2r = d

// Eq. 10 written out here (not Kernels.h): 1 / (pi h^3) (1 - 3/2 q^2 + 3/4 q^3), q <= 1; (2 - q)^3 / (4 pi h^3), q < 2.
double cubicSplineByHand(double r, double h) {
  const double q = r / h, sigma = 1.0 / (kPi * h * h * h);
  if (q >= 2.0) return 0.0;
  if (q > 1.0) return sigma * 0.25 * (2.0 - q) * (2.0 - q) * (2.0 - q);
  return sigma * (1.0 - 1.5 * q * q + 0.75 * q * q * q);
}

// rho / rho0 at point x [m] from particles at `positions` [m], each of mass rho0 d^3: brute force.
double relativeDensityByHand(const std::vector<Eigen::Vector3d>& positions, const Eigen::Vector3d& x) {
  double rho = 0;
  for (const auto& p : positions) rho += kRho0 * kD * kD * kD * cubicSplineByHand((p - x).norm(), kD);
  return rho / kRho0;
}

// The physical centre [m] of voxel (i, j, k) of an image with identity direction.
Eigen::Vector3d centreM(const imaging::ImageType* img, long i, long j, long k) {
  imaging::ImageType::PointType p;
  img->TransformIndexToPhysicalPoint({{i, j, k}}, p);
  return Eigen::Vector3d(p[0], p[1], p[2]) * 1e-3;
}

InjectionRunResult runScaffold(const fs::path& out, bool snapshots) {
  fs::remove_all(out);
  const SceneConfig scene = sceneFromJson({{"tip_mm", {13, 13, 13}},
                                           {"volume_ml", 0.1},
                                           {"snapshot_interval_s", 0.5},
                                           {"cannula_length_mm", 5},
                                           {"simulated_ct_snapshots", snapshots},
                                           {"pressure_model", "equation-of-state"}}); // particles voxelised
  InjectionRunOptions o;
  o.outDir = out.string();
  return runInjection(cementsph::scene::testing::scaffold(), scene, o);
}

} // namespace

TEST(SimulatedCtSnapshots, SceneKeyIsABoolOffByDefault) {
  EXPECT_FALSE(scenePreset("paper").simulatedCtSnapshots);
  const SceneConfig on = sceneFromJson({{"tip_mm", {1, 2, 3}}, {"simulated_ct_snapshots", true}});
  EXPECT_TRUE(on.simulatedCtSnapshots);
  EXPECT_TRUE(toJson(on).at("simulated_ct_snapshots").get<bool>());
  EXPECT_TRUE(sceneFromJson(toJson(on)).simulatedCtSnapshots); // round trip
  try {
    sceneFromJson({{"tip_mm", {1, 2, 3}}}, {"simulated_ct_snapshots=1"});
    FAIL() << "a number was accepted for a bool";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'simulated_ct_snapshots' must be true or false"), std::string::npos)
        << e.what();
  }
}

TEST(SimulatedCtSnapshots, FramesExistMatchTheSnapshotsAndEndAtTheFinalCT) {
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "ct-snapshots";
  const InjectionRunResult r = runScaffold(out, true);
  // 0.1 ml at 0.05 ml/s: 2 s, snapshots at 0.5, 1, 1.5 s and the end: 4, plus the t = 0 frame.
  ASSERT_EQ(r.metrics.at("snapshots").get<int>(), 4);
  EXPECT_EQ(r.metrics.at("simulated_ct_snapshots").get<int>(), 5);
  const double cost = r.metrics.at("simulated_ct_snapshots_wall_s").get<double>();
  EXPECT_TRUE(cost > 0 && cost < r.metrics.at("wall_time_s").get<double>() + 1.0) << cost;

  std::ifstream in(out / "sequence.json");
  ASSERT_TRUE(in) << "no sequence.json";
  const nlohmann::json seq = nlohmann::json::parse(in);
  const auto& frames = seq.at("frames");
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(frames[0].at("simulated_ct").get<std::string>(), "simulated_ct_start.nrrd");
  EXPECT_DOUBLE_EQ(frames[0].at("time_s").get<double>(), 0.0);
  EXPECT_TRUE(frames[0].at("particles").is_null());

  // The particle series' times, read from particles.pvd, are the frames' times.
  std::ifstream pvd(out / "particles.pvd");
  const std::string text((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  const std::regex entry("timestep=\"([^\"]+)\" part=\"0\" file=\"([^\"]+)\"");
  std::size_t k = 1;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it, ++k) {
    ASSERT_LT(k, frames.size());
    EXPECT_EQ(frames[k].at("particles").get<std::string>(), (*it)[2].str());
    EXPECT_NEAR(frames[k].at("time_s").get<double>(), std::stod((*it)[1].str()), 1e-8);
    char expected[64];
    std::snprintf(expected, sizeof expected, "simulated_ct_%04zu.nrrd", k - 1);
    EXPECT_EQ(frames[k].at("simulated_ct").get<std::string>(), expected);
    EXPECT_TRUE(fs::exists(out / expected)) << expected;
    if (k > 1) {
      EXPECT_GT(frames[k].at("time_s").get<double>(), frames[k - 1].at("time_s").get<double>());
    }
  }
  EXPECT_EQ(k, frames.size());
  EXPECT_NEAR(frames.back().at("time_s").get<double>(), r.metrics.at("simulated_time_s").get<double>(), 1e-12);

  // The last frame (= simulated_ct.nrrd) against the voxelisation by hand of the last snapshot's particles.
  const auto start = imaging::readVolume((out / "simulated_ct_start.nrrd").string());
  for (const std::string& name : {frames.back().at("simulated_ct").get<std::string>(), std::string("simulated_ct.nrrd")}) {
    const auto frame = imaging::readVolume((out / name).string());
    const auto poly = imaging::readPolyData((out / frames.back().at("particles").get<std::string>()).string());
    std::vector<Eigen::Vector3d> positions;
    for (vtkIdType p = 0; p < poly->GetNumberOfPoints(); ++p)
      positions.emplace_back(Eigen::Vector3d(poly->GetPoint(p)[0], poly->GetPoint(p)[1], poly->GetPoint(p)[2]) * 1e-3);
    ASSERT_EQ(positions.size(), r.metrics.at("cement_points").get<std::size_t>());
    const auto size = frame->GetLargestPossibleRegion().GetSize();
    double worst = 0, largestRise = 0;
    for (long kk = 0; kk < long(size[2]); ++kk)
      for (long j = 0; j < long(size[1]); ++j)
        for (long i = 0; i < long(size[0]); ++i) {
          const double rise = kHuPerRelative * relativeDensityByHand(positions, centreM(frame, i, j, kk));
          const double expected = double(start->GetPixel({{i, j, kk}})) + rise;
          worst = std::max(worst, std::abs(double(frame->GetPixel({{i, j, kk}})) - expected));
          largestRise = std::max(largestRise, rise);
        }
    std::cout << name << ": largest |HU - HU by hand| " << worst << " HU (largest rise " << largestRise << " HU)\n";
    EXPECT_GT(largestRise, 1000.0) << name; // there is cement to check
    EXPECT_LT(worst, 2e-3) << name;         // float32 HU of ~3000: 2.4e-4 HU per ulp; sums in another order
  }

  // Every frame holds the cement of its particles: the HU rise integrated over the ROI, times V_voxel / k, is
  // the fluid volume N d^3 (the kernel integrates to 1; on 0.5 mm voxels at h = 1.14 mm the known cloud below
  // gives 5e-6; 1e-3 allowed). And N is what the cannula emitted by then: the emitter is volume-exact at the
  // start of each step (Q t' <= N d^3 < Q t' + d^3) and a step is at most one particle interval d^3 / Q long,
  // so Q t - d^3 <= N d^3 < Q t + d^3 at the frame's time t.
  const double q = 0.05e-6, d3 = kD * kD * kD; // m^3/s, the scene's flow rate; m^3
  for (std::size_t f = 1; f < frames.size(); ++f) {
    const auto frame = imaging::readVolume((out / frames[f].at("simulated_ct").get<std::string>()).string());
    const auto poly = imaging::readPolyData((out / frames[f].at("particles").get<std::string>()).string());
    const double particlesVolume = double(poly->GetNumberOfPoints()) * d3;
    const auto sp = frame->GetSpacing();
    const double voxelM3 = sp[0] * sp[1] * sp[2] * 1e-9;
    double rise = 0;
    for (std::size_t i = 0; i < frame->GetLargestPossibleRegion().GetNumberOfPixels(); ++i)
      rise += double(frame->GetBufferPointer()[i]) - double(start->GetBufferPointer()[i]);
    const double volume = rise * voxelM3 / kHuPerRelative, qt = q * frames[f].at("time_s").get<double>();
    std::cout << "frame " << f << ": t " << frames[f].at("time_s").get<double>() << " s, " << poly->GetNumberOfPoints()
              << " particles; cement volume / N d^3 - 1 = " << volume / particlesVolume - 1
              << ", (N d^3 - Q t) / d^3 = " << (particlesVolume - qt) / d3 << "\n";
    EXPECT_NEAR(volume / particlesVolume, 1.0, 1e-3) << f;
    EXPECT_GE(particlesVolume, qt - d3) << f;
    EXPECT_LT(particlesVolume, qt + d3) << f;
  }

  // The t = 0 frame is the scaffold's ROI unchanged (1000 HU rods, -100 HU pores), and the cement makes
  // later frames brighter: the sum over the ROI rises from frame to frame.
  const auto ct = cementsph::scene::testing::scaffold();
  double worst = 0;
  const auto roi = nlohmann::json(r.metrics.at("roi_start_index"));
  const auto size = start->GetLargestPossibleRegion().GetSize();
  for (long kk = 0; kk < long(size[2]); ++kk)
    for (long j = 0; j < long(size[1]); ++j)
      for (long i = 0; i < long(size[0]); ++i) {
        const float a = start->GetPixel({{i, j, kk}});
        const float b = ct->GetPixel({{i + roi[0].get<long>(), j + roi[1].get<long>(), kk + roi[2].get<long>()}});
        worst = std::max(worst, double(std::abs(a - b)));
      }
  EXPECT_EQ(worst, 0.0);
  double previous = -1e300;
  for (const auto& f : frames) {
    const auto v = imaging::readVolume((out / f.at("simulated_ct").get<std::string>()).string());
    double sum = 0;
    for (std::size_t i = 0; i < v->GetLargestPossibleRegion().GetNumberOfPixels(); ++i) sum += v->GetBufferPointer()[i];
    EXPECT_GT(sum, previous) << f.dump();
    previous = sum;
  }
}

TEST(SimulatedCtSnapshots, SimulatedCtOfAKnownCloud) {
  // A 7 x 7 x 7 cubic lattice of spacing d about the scaffold's pore voxel (26, 26, 26) (13 mm; pore: 26 % 10
  // = 6 >= 3), each particle of mass rho0 d^3, voxelised with h = d on the scaffold's ROI.
  const auto ct = cementsph::scene::testing::scaffold();
  const Eigen::Vector3d tipMm(13, 13, 13);
  PorousSolidOptions po;
  po.reachMm = 2 * kD * 1e3;
  const PorousSolid solid = buildPorousSolid(ct, tipMm, po);
  std::vector<Eigen::Vector3d> cloud;
  for (int k = -3; k <= 3; ++k)
    for (int j = -3; j <= 3; ++j)
      for (int i = -3; i <= 3; ++i) cloud.push_back(tipMm * 1e-3 + kD * Eigen::Vector3d(i, j, k));
  std::vector<double> x, y, z, mass;
  for (const auto& p : cloud) x.push_back(p.x()), y.push_back(p.y()), z.push_back(p.z()), mass.push_back(kRho0 * kD * kD * kD);
  const sph::ParticleVoxeliser voxeliser(solid.grid, kD);
  const std::vector<double> dense = voxeliser.density(x.data(), y.data(), z.data(), mass.data(), cloud.size());
  const auto sim = simulatedCtOnRoi(ct, solid, dense, kHuPerRelative, kRho0);

  // The centre voxel sits on a lattice site with a whole support (2h = 2 d) of the lattice around it: by hand,
  // rho / rho0 = (1 + 6/4 + 12 (2 - sqrt 2)^3 / 4 + 8 (2 - sqrt 3)^3 / 4) / pi = 0.9999725 (the site, 6 at
  // q = 1, 12 at sqrt 2, 8 at sqrt 3), so HU = -100 + 3000 * 0.9999725 = 2899.917.
  const double relative = (1.0 + 1.5 + 3.0 * std::pow(2.0 - std::sqrt(2.0), 3) + 2.0 * std::pow(2.0 - std::sqrt(3.0), 3)) / kPi;
  const imaging::ImageType::IndexType centre{{26 - solid.roiStart[0], 26 - solid.roiStart[1], 26 - solid.roiStart[2]}};
  EXPECT_NEAR(sim->GetPixel(centre), -100.0 + kHuPerRelative * relative, 1e-3); // float32: 2.4e-4 HU per ulp
  std::cout << "centre voxel " << sim->GetPixel(centre) << " HU, by hand " << -100.0 + kHuPerRelative * relative << "\n";

  // Every voxel against the brute-force sum; far voxels are the CT's own value exactly; the image holds the
  // cloud's mass (the Riemann sum of the kernel on 0.5 mm voxels, h = 1.14 mm).
  const auto size = sim->GetLargestPossibleRegion().GetSize();
  double worst = 0, rise = 0;
  for (long k = 0; k < long(size[2]); ++k)
    for (long j = 0; j < long(size[1]); ++j)
      for (long i = 0; i < long(size[0]); ++i) {
        const float before = ct->GetPixel({{i + solid.roiStart[0], j + solid.roiStart[1], k + solid.roiStart[2]}});
        const double expected = before + kHuPerRelative * relativeDensityByHand(cloud, centreM(sim, i, j, k));
        worst = std::max(worst, std::abs(sim->GetPixel({{i, j, k}}) - expected));
        rise += double(sim->GetPixel({{i, j, k}})) - before;
      }
  EXPECT_LT(worst, 1e-3);
  const auto sp = sim->GetSpacing();
  const double heldMass = rise / kHuPerRelative * kRho0 * sp[0] * sp[1] * sp[2] * 1e-9;
  const double cloudMass = double(cloud.size()) * kRho0 * kD * kD * kD;
  std::cout << "largest |HU - by hand| " << worst << " HU; held mass / cloud mass - 1 = " << heldMass / cloudMass - 1 << "\n";
  EXPECT_NEAR(heldMass / cloudMass, 1.0, 1e-3);

  // The same image from the density where it is not zero (the result's images take it so: issue 23, no
  // region-sized array); the oracles are the dense pass above (every voxel equal as a number) and the CT itself
  // (a voxel without cement is the CT's value bit for bit).
  const auto& a = sim;
  std::size_t nonZero = 0;
  for (double r : dense) nonZero += r != 0;
  const SparseDensity sparse = nonZeroDensity(dense);
  ASSERT_EQ(sparse.size(), nonZero);
  ASSERT_GT(nonZero, 100u);
  ASSERT_LT(nonZero, dense.size() / 2); // most of the region holds no cement
  const auto b = simulatedCtOnRoi(ct, solid, sparse, kHuPerRelative, kRho0);
  ASSERT_EQ(a->GetLargestPossibleRegion(), b->GetLargestPossibleRegion());
  EXPECT_EQ(a->GetOrigin(), b->GetOrigin());
  const std::size_t n = a->GetLargestPossibleRegion().GetNumberOfPixels();
  std::size_t differ = 0, notTheCt = 0;
  for (std::size_t c = 0; c < n; ++c) {
    differ += a->GetBufferPointer()[c] != b->GetBufferPointer()[c];
    if (dense[c] == 0) {
      const long nx = solid.grid.size[0], ny = solid.grid.size[1];
      const long i = long(c) % nx, j = (long(c) / nx) % ny, k = long(c) / (nx * ny);
      const float before = ct->GetPixel({{i + solid.roiStart[0], j + solid.roiStart[1], k + solid.roiStart[2]}});
      notTheCt += std::memcmp(&before, b->GetBufferPointer() + c, sizeof(float)) != 0;
    }
  }
  EXPECT_EQ(differ, 0u);
  EXPECT_EQ(notTheCt, 0u);
  // A voxel out of order or outside the region is refused, not written.
  SparseDensity bad = sparse;
  std::swap(bad[3], bad[4]);
  EXPECT_THROW(simulatedCtOnRoi(ct, solid, bad, kHuPerRelative, kRho0), std::invalid_argument);
  bad = {{dense.size(), 1.0}};
  EXPECT_THROW(simulatedCtOnRoi(ct, solid, bad, kHuPerRelative, kRho0), std::invalid_argument);
}

TEST(SimulatedCtSnapshots, OffWritesNoFrames) {
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "ct-snapshots-off";
  const InjectionRunResult r = runScaffold(out, false);
  EXPECT_FALSE(r.metrics.contains("simulated_ct_snapshots"));
  EXPECT_FALSE(fs::exists(out / "sequence.json"));
  EXPECT_FALSE(fs::exists(out / "simulated_ct_start.nrrd"));
  EXPECT_FALSE(fs::exists(out / "simulated_ct_0000.nrrd"));
  EXPECT_TRUE(fs::exists(out / "simulated_ct.nrrd"));
}
