// The default creeping-flow path of `cementsph inject` (pressure_model voxel-darcy, src/Models/VoxelDarcy)
// on a synthetic porous CT (ScaffoldCT.h), against the issue "Physical cement"'s oracles on a CT:
//  * the pressure is proportional to the viscosity: 400 against 100 Pa s, tip and injection pressure 4.00
//    within 2 %, and the same cement (simulated CTs equal to 0.01 HU, so the surfaces coincide);
//  * the cement's volume is the injected volume at every snapshot (within 1 %; by construction to 1e-9);
//  * no cement in a solid voxel (read from the simulated CT against the input's HU);
//  * the files of an injection, and the metrics' keys;
//  * with snapshot_arrays "flow", every snapshot file, read back with VTK's reader, holds the volume injected at
//    its time (flow rate x time) and the interstitial velocity darcy_velocity / porosity, one vertex cell per
//    point (issue 23: the snapshots are written on a second thread while the run goes on, with 32-bit vertex
//    ids), and the snapshots before the last leave out only what the last snapshot and their own arrays give;
//  * with "growth" (the default), each snapshot before the last is the cement that had arrived by its time,
//    read by VTK's parallel reader from pieces merged four at a time (InjectionWriter::snapshotPiece).
#include "cementsph/imaging/PolyDataIO.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/InjectionRunner.h"
#include "ScaffoldCT.h"

#include <gtest/gtest.h>
#include <itkImageRegionConstIterator.h>
#include <itkImageRegionConstIteratorWithIndex.h>
#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkFieldData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkXMLPPolyDataReader.h>
#include <vtkXMLPolyDataReader.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <set>
#include <sstream>

using namespace cementsph;
using namespace cementsph::scene;
namespace fs = std::filesystem;

namespace {

InjectionRunResult run(double viscosityPaS, const fs::path& out, double snapshotIntervalS = 1.0,
                       const std::string& snapshotArrays = "growth") {
  fs::remove_all(out);
  const SceneConfig scene = sceneFromJson({{"tip_mm", {13, 13, 13}},
                                           {"volume_ml", 0.3},
                                           {"viscosity_pa_s", viscosityPaS},
                                           {"snapshot_interval_s", snapshotIntervalS},
                                           {"snapshot_arrays", snapshotArrays},
                                           {"cannula_length_mm", 5}});
  InjectionRunOptions o;
  o.outDir = out.string();
  return runInjection(cementsph::scene::testing::scaffold(), scene, o);
}

} // namespace

TEST(VoxelDarcyInjection, PressureFollowsViscosityAndTheCementKeepsItsVolumeAndItsPores) {
  const fs::path scratch = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch";
  const InjectionRunResult low = run(100.0, scratch / "voxel-darcy-100"), high = run(400.0, scratch / "voxel-darcy-400");
  const nlohmann::json &a = low.metrics, &b = high.metrics;
  EXPECT_EQ(a["pressure_model"], "voxel-darcy");
  EXPECT_EQ(a["model"], "incompressible-darcy-on-voxels");
  EXPECT_TRUE(a["pressure_is_physical"].get<bool>());
  for (const char* key : {"final_tip_pressure_pa", "max_tip_pressure_pa", "cannula_pressure_drop_pa",
                          "injection_pressure_pa", "max_injection_pressure_pa"}) {
    ASSERT_GT(a[key].get<double>(), 0.0) << key;
    EXPECT_NEAR(b[key].get<double>() / a[key].get<double>(), 4.0, 0.08) << key;
  }
  // The same cement: the simulated CTs agree voxel by voxel.
  double worst = 0;
  itk::ImageRegionConstIterator<imaging::ImageType> x(low.simulatedCt, low.simulatedCt->GetLargestPossibleRegion());
  itk::ImageRegionConstIterator<imaging::ImageType> y(high.simulatedCt, high.simulatedCt->GetLargestPossibleRegion());
  for (; !x.IsAtEnd(); ++x, ++y) worst = std::max(worst, double(std::abs(x.Get() - y.Get())));
  EXPECT_LT(worst, 0.01);

  // Volume at every snapshot.
  ASSERT_GE(a["volume_history"].size(), 6u); // snapshots at 1..5 s and the end (6 s)
  for (const auto& r : a["volume_history"]) {
    const double injected = r["volume_injected_ml"].get<double>(), held = r["cement_volume_ml"].get<double>();
    EXPECT_NEAR(held, injected, 0.01 * injected) << "at " << r["time_s"] << " s";
  }
  EXPECT_NEAR(a["volume_injected_ml"].get<double>(), 0.3, 1e-9);
  // The scaffold's rods (1000 HU) hold no cement: their simulated HU is the CT's.
  const auto ct = cementsph::scene::testing::scaffold();
  itk::ImageRegionConstIteratorWithIndex<imaging::ImageType> s(low.simulatedCt, low.simulatedCt->GetLargestPossibleRegion());
  std::size_t rods = 0, cement = 0;
  for (; !s.IsAtEnd(); ++s) {
    const auto idx = s.GetIndex();
    if (cementsph::scene::testing::scaffoldRod(int(idx[0]), int(idx[1]), int(idx[2]))) {
      ++rods;
      EXPECT_FLOAT_EQ(s.Get(), 1000.f) << idx;
    } else if (s.Get() > -100.f + 1500.f) {
      ++cement;
    }
  }
  EXPECT_EQ(rods, 13824u);
  // At least half full in 0.3 ml / 0.125 mm^3 = 2400 voxels (the front's voxels are partly filled).
  EXPECT_GT(cement, 2000u);
  EXPECT_LT(cement, 2400u);

  // Files, and the points of a snapshot: one per voxel holding cement, with their arrays.
  const fs::path out = scratch / "voxel-darcy-100";
  for (const char* f : {"metrics.json", "tip_pressure.csv", "particles.pvd", "simulated_ct.nrrd", "scene.json",
                        "particles_0000.pvtp", "particles_piece_0000.vtp", "particles_0005.vtp"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  auto poly = imaging::readPolyData((out / "particles_0005.vtp").string());
  EXPECT_EQ(std::size_t(poly->GetNumberOfPoints()), a["cement_voxels"].get<std::size_t>());
  for (const char* n : {"fill_fraction", "cement_volume_mm3", "pressure_pa", "darcy_velocity_m_per_s",
                        "viscosity_pa_s", "porosity", "permeability_m2", "arrival_time_s", "age_s"})
    EXPECT_NE(poly->GetPointData()->GetArray(n), nullptr) << n;
  double volumeMm3 = 0;
  auto* v = poly->GetPointData()->GetArray("cement_volume_mm3");
  for (vtkIdType i = 0; i < v->GetNumberOfTuples(); ++i) volumeMm3 += v->GetTuple1(i);
  EXPECT_NEAR(volumeMm3, 300.0, 1e-6);
}

TEST(VoxelDarcyInjection, APowerLawOfIndexOneIsTheNewtonianRunAndTheKeysAreChecked) {
  const nlohmann::json base{{"tip_mm", {13, 13, 13}}, {"volume_ml", 0.1}, {"snapshot_interval_s", 10.0}, {"cannula_length_mm", 5}};
  const InjectionRunResult newtonian = runInjection(cementsph::scene::testing::scaffold(), sceneFromJson(base), {});
  nlohmann::json pl = base;
  pl["viscosity_law"] = "power-law";
  pl["consistency_pa_s_n"] = 100.0;
  pl["flow_index"] = 1.0;
  const InjectionRunResult power = runInjection(cementsph::scene::testing::scaffold(), sceneFromJson(pl), {});
  for (const char* key : {"final_tip_pressure_pa", "cannula_pressure_drop_pa", "mean_spreading_distance_mm"})
    EXPECT_NEAR(power.metrics[key].get<double>(), newtonian.metrics[key].get<double>(),
                1e-9 * std::abs(newtonian.metrics[key].get<double>())) << key;
  EXPECT_EQ(power.metrics["viscosity_law"], "power-law");
  // A law the particle models do not have, and parameters out of range: one clear error each.
  nlohmann::json eos = pl;
  eos["pressure_model"] = "equation-of-state";
  EXPECT_THROW(runInjection(cementsph::scene::testing::scaffold(), sceneFromJson(eos), {}), std::invalid_argument);
  pl["flow_index"] = -1.0;
  EXPECT_THROW(sceneFromJson(pl), std::invalid_argument);
  pl["flow_index"] = 0.5;
  pl["cannula_gauge"] = "99G";
  EXPECT_THROW(sceneFromJson(pl), std::invalid_argument);
}

TEST(VoxelDarcyInjection, ACuringCementMultipliesThePowerLawsConsistency) {
  // CMW 1 at 25 C (75e3 Pa s at 522 s after mixing, Nicholas et al. 2007), K = 100 Pa s^n at 120 s after
  // mixing, injected from 240 s after mixing: 0.1 ml at 0.05 ml/s, T = 2 s. The cannula's drop is the power
  // law's closed form with K times the curing factor, 2 f K L / R ((3n+1)/n Q/(pi R^3))^n, written out here.
  const nlohmann::json scene{{"tip_mm", {13, 13, 13}}, {"volume_ml", 0.1}, {"snapshot_interval_s", 10.0},
                             {"cannula_length_mm", 5}, {"viscosity_law", "power-law"}, {"consistency_pa_s_n", 100.0},
                             {"flow_index", 0.5}, {"cement", "cmw1-25c"}, {"curing_reference_time_s", 120.0},
                             {"mixing_to_injection_s", 240.0}};
  const InjectionRunResult r = runInjection(cementsph::scene::testing::scaffold(), sceneFromJson(scene), {});
  const double tau = (522.0 - 120.0) / std::log(75e3 / 100.0), T = 2.0;
  const double fEnd = std::exp((240.0 + T - 120.0) / tau);
  EXPECT_EQ(r.metrics["curing_model"], "exponential");
  EXPECT_NEAR(r.metrics["curing_factor_at_end"].get<double>(), fEnd, 1e-9 * fEnd);
  EXPECT_NEAR(r.metrics["curing_factor_at_start"].get<double>(), std::exp(120.0 / tau), 1e-9);
  const double K = 100, n = 0.5, L = 5e-3, Q = 0.05e-6, R = 0.5 * 2.388e-3, pi = 3.14159265358979323846;
  const double drop = 2 * fEnd * K * L / R * std::pow((3 * n + 1) / n * Q / (pi * R * R * R), n);
  // The last step (at most 1 % of T) takes the factor at its start: exp(-0.01 T / tau) below fEnd at worst.
  EXPECT_NEAR(r.metrics["cannula_pressure_drop_pa"].get<double>() / drop, 1.0, 0.01 * T / tau + 1e-9);
  // The particle models are Newtonian without curing: one clear error.
  nlohmann::json eos = scene;
  eos["viscosity_law"] = "newtonian";
  eos["pressure_model"] = "equation-of-state";
  EXPECT_THROW(runInjection(cementsph::scene::testing::scaffold(), sceneFromJson(eos), {}), std::invalid_argument);
}

TEST(VoxelDarcyInjection, EverySnapshotFileHoldsTheVolumeInjectedAtItsTime) {
  // 0.3 ml at the scene's 0.05 ml/s (6 s) with a snapshot every 0.25 s: 24 files, more than the writer's queue
  // holds, so the run waits on the writer now and then.
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "voxel-darcy-snapshots";
  run(100.0, out, 0.25, "flow");
  const double flowMm3PerS = 0.05e3;
  std::ifstream pvdFile(out / "particles.pvd");
  std::stringstream pvd;
  pvd << pvdFile.rdbuf();
  const std::string text = pvd.str();
  const std::regex entry("timestep=\"([^\"]+)\" part=\"0\" file=\"([^\"]+)\"");
  std::size_t files = 0, filesWithVelocity = 0;
  vtkIdType previousPoints = 0;
  const auto entries = std::size_t(std::distance(std::sregex_iterator(text.begin(), text.end(), entry), std::sregex_iterator()));
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it, ++files) {
    const double t = std::stod((*it)[1]);
    const std::string name = (*it)[2];
    auto reader = vtkSmartPointer<vtkXMLPolyDataReader>::New();
    reader->SetFileName((out / name).string().c_str());
    reader->Update();
    ASSERT_EQ(reader->GetErrorCode(), 0) << name;
    vtkPolyData* poly = reader->GetOutput();
    const vtkIdType n = poly->GetNumberOfPoints();
    ASSERT_GT(n, 0) << name;
    EXPECT_GE(n, previousPoints) << name; // cement is only ever added
    previousPoints = n;
    // The cement's volume is the injected volume by construction (the inflows add up to the flow rate), to
    // round-off; the fill of the front voxels does not move it.
    auto* volume = poly->GetPointData()->GetArray("cement_volume_mm3");
    ASSERT_NE(volume, nullptr) << name;
    double mm3 = 0;
    for (vtkIdType i = 0; i < n; ++i) mm3 += volume->GetTuple1(i);
    EXPECT_NEAR(mm3, flowMm3PerS * t, 1e-6 * flowMm3PerS * t) << name << " at " << t << " s";
    // One vertex cell per point, point i in cell i.
    ASSERT_EQ(poly->GetNumberOfCells(), n) << name;
    ASSERT_EQ(poly->GetVerts()->GetNumberOfCells(), n) << name;
    EXPECT_EQ(poly->GetCellType(n - 1), VTK_VERTEX) << name;
    EXPECT_EQ(poly->GetVerts()->GetConnectivityArray()->GetTuple1(n - 1), double(n - 1)) << name;
    // The cement's own velocity is the Darcy flux over the porosity (float arrays: 1e-6 relative), in the files
    // that hold both: the last one (the earlier ones leave them out, issue 23; the next test checks that).
    auto *q = poly->GetPointData()->GetArray("darcy_velocity_m_per_s"), *v = poly->GetPointData()->GetArray("velocity_m_per_s"),
         *phi = poly->GetPointData()->GetArray("porosity");
    ASSERT_NE(q, nullptr) << name;
    ASSERT_EQ(v == nullptr, phi == nullptr) << name;
    if (!v) continue;
    ++filesWithVelocity;
    EXPECT_EQ(files + 1, entries) << name << ": only the last snapshot holds velocity_m_per_s and porosity";
    double worst = 0;
    for (vtkIdType i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) {
        const double expected = q->GetComponent(i, a) / phi->GetTuple1(i);
        worst = std::max(worst, std::abs(v->GetComponent(i, a) - expected) / std::max(std::abs(expected), 1e-12));
      }
    EXPECT_LT(worst, 1e-6) << name;
  }
  EXPECT_EQ(files, 24u); // at 0.25, 0.5, ..., 5.75 s and the end (6 s)
  EXPECT_EQ(filesWithVelocity, 1u);
}

TEST(VoxelDarcyInjection, TheEarlierSnapshotsLeaveOutOnlyWhatTheLastOneAndTheirOwnArraysGive) {
  // snapshot_arrays "flow": 0.3 ml in 6 s, a snapshot every 2 s: particles_0000 (2 s), 0001 (4 s), 0002 (the
  // end, 6 s). The earlier ones hold the point arrays cement_volume_mm3, pressure_pa, darcy_velocity_m_per_s
  // (issue 23: what changes while the cement flows) and, the cement being Newtonian at one viscosity, the
  // scene's 100 Pa s as one field-data value viscosity_pa_s; the last holds every array. What they leave out is
  // there: every voxel of an earlier snapshot is in the last with the same position and arrived no later than
  // its snapshot's time, its fill is cement_volume_mm3 / (the last one's porosity x voxel volume) with the
  // voxel's 0.5 mm edge, its velocity is its darcy_velocity_m_per_s over that porosity, and its density the
  // field-data value density_kg_per_m3 every snapshot holds, which is the last one's density at every point
  // (incompressible).
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "voxel-darcy-reduced-snapshots";
  run(100.0, out, 2.0, "flow");
  const auto last = imaging::readPolyData((out / "particles_0002.vtp").string());
  vtkPointData* lastData = last->GetPointData();
  for (const char* name : {"fill_fraction", "permeability_m2", "arrival_time_s", "age_s", "cement_volume_mm3", "porosity",
                           "velocity_m_per_s", "density_kg_per_m3", "pressure_pa", "darcy_velocity_m_per_s", "viscosity_pa_s"})
    ASSERT_NE(lastData->GetArray(name), nullptr) << name;
  auto fieldValue = [](vtkPolyData* poly, const char* name) {
    vtkDataArray* a = poly->GetFieldData()->GetArray(name);
    return a && a->GetNumberOfTuples() == 1 ? a->GetTuple1(0) : -1.0;
  };
  const double density = lastData->GetArray("density_kg_per_m3")->GetTuple1(0);
  EXPECT_GT(density, 0.0);
  for (vtkIdType i = 0; i < last->GetNumberOfPoints(); ++i)
    ASSERT_EQ(lastData->GetArray("density_kg_per_m3")->GetTuple1(i), density) << "point " << i;
  EXPECT_NEAR(fieldValue(last, "density_kg_per_m3"), density, 1e-4 * density);
  auto key = [](const double* x) {
    return std::to_string(std::lround(x[0] * 1e3)) + "," + std::to_string(std::lround(x[1] * 1e3)) + "," +
           std::to_string(std::lround(x[2] * 1e3));
  };
  std::map<std::string, vtkIdType> inLast;
  for (vtkIdType i = 0; i < last->GetNumberOfPoints(); ++i) inLast[key(last->GetPoint(i))] = i;
  const double voxelMm3 = 0.5 * 0.5 * 0.5;
  for (const auto& [file, t] : {std::pair<const char*, double>{"particles_0000.vtp", 2.0}, {"particles_0001.vtp", 4.0}}) {
    const auto poly = imaging::readPolyData((out / file).string());
    vtkPointData* d = poly->GetPointData();
    EXPECT_EQ(d->GetNumberOfArrays(), 3) << file; // the three below
    EXPECT_NEAR(fieldValue(poly, "density_kg_per_m3"), density, 1e-4 * density) << file;
    EXPECT_EQ(fieldValue(poly, "viscosity_pa_s"), 100.0) << file; // the scene's, one value
    auto *volume = d->GetArray("cement_volume_mm3"), *q = d->GetArray("darcy_velocity_m_per_s"), *p = d->GetArray("pressure_pa");
    ASSERT_TRUE(volume && q && p) << file;
    ASSERT_GT(poly->GetNumberOfPoints(), 100) << file;
    double latestArrival = 0, fastest = 0;
    for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i) {
      const auto at = inLast.find(key(poly->GetPoint(i)));
      ASSERT_NE(at, inLast.end()) << file << " point " << i;
      latestArrival = std::max(latestArrival, lastData->GetArray("arrival_time_s")->GetTuple1(at->second));
      const double phi = lastData->GetArray("porosity")->GetTuple1(at->second);
      ASSERT_GT(phi, 0.0) << file << " point " << i;
      const double fill = volume->GetTuple1(i) / (phi * voxelMm3);
      EXPECT_GT(fill, 0.0) << file << " point " << i;
      EXPECT_LE(fill, 1.0 + 1e-6) << file << " point " << i;
      fastest = std::max(fastest, std::abs(q->GetComponent(i, 0) / phi));
    }
    EXPECT_LE(latestArrival, t * (1 + 1e-6)) << file;
    EXPECT_GT(fastest, 0.0) << file; // the cement still moves: the velocities were there to leave out
  }
}

TEST(VoxelDarcyInjection, GrowthSnapshotsAreTheCementThatHadArrived) {
  // snapshot_arrays "growth" (the default): 0.3 ml in 6 s, a snapshot every 0.5 s. Each snapshot before the
  // last is particles_NNNN.pvtp, the union of pieces, read here with VTK's parallel reader. Oracles:
  //  * the same scene with "flow", whose .vtp snapshots come from the other path (every voxel's state,
  //    runningCementToPolyData): the growth snapshot at t holds exactly that snapshot's voxels, each once;
  //  * the last snapshot (every array, cementVoxelsToPolyData): each voxel's arrival_time_s, exactly, and at
  //    most t;
  //  * the pieces are a base-4 counter's digits (InjectionWriter::snapshotPiece): snapshot k names as many
  //    pieces as the digits of k + 1 written in base 4 add up to (12 snapshots: 1, 2, 3, 1, 2, ...).
  const fs::path out = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "voxel-darcy-growth";
  const fs::path flow = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / "voxel-darcy-growth-flow";
  run(100.0, out, 0.5);
  run(100.0, flow, 0.5, "flow");
  std::ifstream pvdFile(out / "particles.pvd");
  std::stringstream pvd;
  pvd << pvdFile.rdbuf();
  const std::string text = pvd.str();
  const std::regex entry("timestep=\"([^\"]+)\" part=\"0\" file=\"([^\"]+)\"");
  std::vector<std::pair<double, std::string>> series;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it)
    series.emplace_back(std::stod((*it)[1]), (*it)[2]);
  ASSERT_EQ(series.size(), 12u); // 0.5, 1, ..., 5.5 s and the end (6 s)
  ASSERT_EQ(series.back().second, "particles_0011.vtp");
  const auto last = imaging::readPolyData((out / series.back().second).string());
  vtkDataArray* lastArrival = last->GetPointData()->GetArray("arrival_time_s");
  ASSERT_NE(lastArrival, nullptr);
  auto key = [](const double* x) {
    return std::to_string(std::lround(x[0] * 1e3)) + "," + std::to_string(std::lround(x[1] * 1e3)) + "," +
           std::to_string(std::lround(x[2] * 1e3));
  };
  std::map<std::string, double> arrivalInLast;
  for (vtkIdType i = 0; i < last->GetNumberOfPoints(); ++i) arrivalInLast[key(last->GetPoint(i))] = lastArrival->GetTuple1(i);
  const std::regex pieceEntry("<Piece Source=\"([^\"]+)\"/>");
  for (std::size_t k = 0; k + 1 < series.size(); ++k) {
    const auto& [t, name] = series[k];
    char expected[64];
    std::snprintf(expected, sizeof expected, "particles_%04zu.pvtp", k);
    ASSERT_EQ(name, expected);
    std::ifstream unionFile(out / name);
    std::stringstream unionText;
    unionText << unionFile.rdbuf();
    const std::string u = unionText.str();
    std::size_t pieces = 0;
    for (auto it = std::sregex_iterator(u.begin(), u.end(), pieceEntry); it != std::sregex_iterator(); ++it, ++pieces)
      EXPECT_TRUE(fs::exists(out / (*it)[1].str())) << name << " names " << (*it)[1];
    std::size_t digits = 0;
    for (std::size_t count = k + 1; count > 0; count /= 4) digits += count % 4;
    EXPECT_EQ(pieces, digits) << name;
    auto reader = vtkSmartPointer<vtkXMLPPolyDataReader>::New();
    reader->SetFileName((out / name).string().c_str());
    reader->Update();
    ASSERT_EQ(reader->GetErrorCode(), 0) << name;
    vtkPolyData* snapshot = reader->GetOutput();
    vtkDataArray* arrival = snapshot->GetPointData()->GetArray("arrival_time_s");
    ASSERT_NE(arrival, nullptr) << name;
    EXPECT_EQ(snapshot->GetNumberOfVerts(), snapshot->GetNumberOfPoints()) << name;
    std::set<std::string> held;
    for (vtkIdType i = 0; i < snapshot->GetNumberOfPoints(); ++i) {
      const std::string at = key(snapshot->GetPoint(i));
      EXPECT_TRUE(held.insert(at).second) << name << " point " << i << " twice";
      const auto inLast = arrivalInLast.find(at);
      ASSERT_NE(inLast, arrivalInLast.end()) << name << " point " << i << " is not in the last snapshot";
      EXPECT_EQ(arrival->GetTuple1(i), inLast->second) << name << " point " << i;
      EXPECT_LE(arrival->GetTuple1(i), t * (1 + 1e-6)) << name << " point " << i;
    }
    char flowName[64];
    std::snprintf(flowName, sizeof flowName, "particles_%04zu.vtp", k);
    const auto flowSnapshot = imaging::readPolyData((flow / flowName).string());
    std::set<std::string> flowHeld;
    for (vtkIdType i = 0; i < flowSnapshot->GetNumberOfPoints(); ++i) flowHeld.insert(key(flowSnapshot->GetPoint(i)));
    EXPECT_EQ(held, flowHeld) << name << " against the flow run's " << flowName;
    EXPECT_GT(held.size(), 0u) << name;
  }
}
