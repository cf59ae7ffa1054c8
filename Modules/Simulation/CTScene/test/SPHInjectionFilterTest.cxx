// vtkSPHInjectionFilter in a VTK pipeline: the scaffold CT in (vtkImageData, through SetInputData and through a
// producer's SetInputConnection); out the simulated CT (port 0) and the cement label map (port 1), both on the
// input's grid, and the cement points (port 2); the optional bone mask (port 1 in); setters, progress events,
// abort, and errors reported without a VTK error print.
#include "ScaffoldCT.h"

#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"
#include "vtkSPHInjectionFilter.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <omp.h>
#include <vtkCallbackCommand.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkTrivialProducer.h>

#include <cstdint>
#include <filesystem>
#include <iterator>
#include <string>

#include <cmath>

namespace {
const int kOneThread = [] {
  omp_set_num_threads(1);
  return 1;
}();

struct ProgressLog {
  int events = 0;
  double last = -1;
  bool monotone = true;
  double abortAt = 2.0; // abort once progress reaches this
};

void onProgress(vtkObject* caller, unsigned long, void* clientData, void* callData) {
  auto* log = static_cast<ProgressLog*>(clientData);
  const double p = *static_cast<double*>(callData);
  ++log->events;
  if (p < log->last) log->monotone = false;
  log->last = p;
  if (p >= log->abortAt) static_cast<vtkSPHInjectionFilter*>(caller)->SetAbortExecute(1);
}

vtkSmartPointer<vtkSPHInjectionFilter> makeFilter(vtkImageData* ct, ProgressLog& log) {
  auto filter = vtkSmartPointer<vtkSPHInjectionFilter>::New();
  filter->SetInputData(ct);
  filter->SetTipMm(13, 13, 13);
  filter->SetVolumeMl(0.1);
  filter->SetCannulaLengthMm(5);
  auto cb = vtkSmartPointer<vtkCallbackCommand>::New();
  cb->SetCallback(onProgress);
  cb->SetClientData(&log);
  filter->AddObserver(vtkCommand::ProgressEvent, cb);
  return filter;
}
} // namespace

TEST(SPHInjectionFilter, ParticlesAndSimulatedCTFromACTImage) {
  vtkSmartPointer<vtkImageData> ct = cementsph::imaging::toVtk(cementsph::scene::testing::scaffold());
  ProgressLog log;
  auto filter = makeFilter(ct, log);
  EXPECT_DOUBLE_EQ(filter->GetFlowRateMlPerS(), 0.05); // the paper scene's values by default
  EXPECT_DOUBLE_EQ(filter->GetROISizeMm(), 40.0);
  filter->Update();
  ASSERT_EQ(filter->GetErrorMessage(), "");
  const nlohmann::json m = nlohmann::json::parse(filter->GetMetricsJSON());
  const double d3 = std::pow(1.14e-3, 3) * 1e6;
  EXPECT_GT(m["volume_injected_ml"].get<double>(), 0.1 - d3);
  EXPECT_LE(m["volume_injected_ml"].get<double>(), 0.1);
  vtkPolyData* particles = filter->GetParticlesOutput();
  ASSERT_NE(particles, nullptr);
  EXPECT_EQ(std::size_t(particles->GetNumberOfPoints()), m["cement_points"].get<std::size_t>());
  EXPECT_EQ(particles->GetNumberOfVerts(), particles->GetNumberOfPoints());
  EXPECT_EQ(particles, filter->GetOutputDataObject(vtkSPHInjectionFilter::CementPointsPort)); // port 2
  for (const char* a : {"velocity_m_per_s", "density_kg_per_m3", "pressure_pa", "age_s"})
    EXPECT_NE(particles->GetPointData()->GetArray(a), nullptr) << a;
  vtkImageData* sim = filter->GetSimulatedCTOutput();
  ASSERT_NE(sim, nullptr);
  EXPECT_EQ(sim, filter->GetOutputDataObject(vtkSPHInjectionFilter::SimulatedCTPort)); // port 0
  int dims[3];
  sim->GetDimensions(dims);
  EXPECT_EQ(dims[0], 40);
  EXPECT_EQ(dims[2], 40);
  EXPECT_FLOAT_EQ(sim->GetScalarComponentAsFloat(5, 5, 5, 0), -100.f);       // far from the cement
  EXPECT_GT(sim->GetScalarComponentAsFloat(26, 26, 28, 0), 900.f);          // 1 mm ahead of the tip
  EXPECT_GT(log.events, 50); // every 1 % of the injection time
  EXPECT_TRUE(log.monotone);
  EXPECT_DOUBLE_EQ(log.last, 1.0);
  // Pipeline: a second Update without changes does not rerun; a setter does.
  const int events = log.events;
  const vtkIdType first = particles->GetNumberOfPoints();
  filter->Update();
  EXPECT_EQ(log.events, events);
  filter->SetVolumeMl(0.05);
  filter->Update();
  EXPECT_GT(log.events, events);
  EXPECT_LT(filter->GetParticlesOutput()->GetNumberOfPoints(), first); // half the volume
}

TEST(SPHInjectionFilter, ErrorsAreKeptAndRethrown) {
  vtkSmartPointer<vtkImageData> ct = cementsph::imaging::toVtk(cementsph::scene::testing::scaffold());
  ProgressLog log;
  auto filter = makeFilter(ct, log);
  filter->SetTipMm(0.5, 0.5, 13); // in a rod
  filter->Update();
  EXPECT_NE(filter->GetErrorMessage().find("lies in solid"), std::string::npos) << filter->GetErrorMessage();
  EXPECT_THROW(filter->RethrowIfFailed(), std::invalid_argument);
  EXPECT_EQ(filter->GetParticlesOutput()->GetNumberOfPoints(), 0);
  filter->SetTipMm(13, 13, 13);
  filter->SetViscosityPaS(-1);
  filter->Update();
  EXPECT_NE(filter->GetErrorMessage().find("'viscosity_pa_s'"), std::string::npos) << filter->GetErrorMessage();
}

TEST(SPHInjectionFilter, AbortStopsTheRun) {
  vtkSmartPointer<vtkImageData> ct = cementsph::imaging::toVtk(cementsph::scene::testing::scaffold());
  ProgressLog log;
  log.abortAt = 0.0; // abort at the first report
  auto filter = makeFilter(ct, log);
  filter->SetVolumeMl(1.0);
  filter->Update();
  ASSERT_EQ(filter->GetErrorMessage(), "");
  const nlohmann::json m = nlohmann::json::parse(filter->GetMetricsJSON());
  EXPECT_TRUE(m["stopped_early"].get<bool>());
  EXPECT_LT(m["simulated_time_s"].get<double>(), 1.0);
}

namespace {
// The scaffold's voxel (i, j, k) of the label map / simulated CT / input, flat in VTK's point order.
vtkIdType flat(int i, int j, int k, int n = 40) { return vtkIdType(i) + vtkIdType(n) * (vtkIdType(j) + vtkIdType(n) * vtkIdType(k)); }
} // namespace

// The label map (port 1) on the input's grid. Oracles independent of the filter: the scaffold's own geometry
// (ScaffoldCT.h: rods solid, so no cement label on a rod voxel), the injected volume as flow x time (0.1 ml
// at 0.05 ml/s for 2 s), pores of porosity 1 (pore-resolved: -100 HU below threshold_hu 0), so the cement
// fills 0.1 ml / 0.125 mm^3 = 800 voxels; labelled voxels (at least half filled) within 10 % of that (the
// front's part-filled voxels are counted when at least half full: a front of ~400 voxels at a mean fill
// near 1/2 moves the count by a few per cent either way).
TEST(SPHInjectionFilter, LabelMapOnTheInputGridHoldsTheInjectedVolume) {
  vtkSmartPointer<vtkImageData> ct = cementsph::imaging::toVtk(cementsph::scene::testing::scaffold());
  ct->SetOrigin(-3.0, 2.0, 5.5); // not the origin: the outputs must keep it
  ProgressLog log;
  auto filter = makeFilter(ct, log);
  filter->SetTipMm(13 - 3.0, 13 + 2.0, 13 + 5.5);
  filter->Update();
  ASSERT_EQ(filter->GetErrorMessage(), "");
  vtkImageData* labels = filter->GetLabelMapOutput();
  vtkImageData* sim = filter->GetSimulatedCTOutput();
  ASSERT_NE(labels, nullptr);
  EXPECT_EQ(labels, filter->GetOutputDataObject(vtkSPHInjectionFilter::LabelMapPort));
  EXPECT_EQ(labels->GetScalarType(), VTK_UNSIGNED_CHAR);
  for (vtkImageData* out : {labels, sim}) {
    int extent[6];
    out->GetExtent(extent);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(extent[2 * a], 0);
      EXPECT_EQ(extent[2 * a + 1], 39);
      EXPECT_DOUBLE_EQ(out->GetOrigin()[a], ct->GetOrigin()[a]);
      EXPECT_DOUBLE_EQ(out->GetSpacing()[a], 0.5);
    }
  }
  const auto* l = static_cast<const std::uint8_t*>(labels->GetScalarPointer());
  std::size_t cement = 0, onRods = 0, leaked = 0, riseBelowHalf = 0;
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        const std::uint8_t v = l[flat(i, j, k)];
        if (v == vtkSPHInjectionFilter::LeakedCement) ++leaked;
        if (v != vtkSPHInjectionFilter::Cement) continue;
        ++cement;
        if (cementsph::scene::testing::scaffoldRod(i, j, k)) ++onRods;
        // A labelled voxel is at least half filled: the simulated CT rose by at least k/2 = 1500 HU there.
        if (sim->GetScalarComponentAsDouble(i, j, k, 0) - ct->GetScalarComponentAsDouble(i, j, k, 0) < 1500.0 - 1e-3)
          ++riseBelowHalf;
      }
  EXPECT_EQ(onRods, 0u);
  EXPECT_EQ(leaked, 0u); // no mask, pore-resolved bone: the engine assesses no leakage
  EXPECT_EQ(riseBelowHalf, 0u);
  const double oracleVoxels = 0.05 * 2.0 * 1e3 / (0.5 * 0.5 * 0.5); // ml -> mm^3, over the voxel volume
  EXPECT_NEAR(double(cement), oracleVoxels, 0.10 * oracleVoxels);
  // The tip's voxel is cement.
  EXPECT_EQ(l[flat(26, 26, 26)], vtkSPHInjectionFilter::Cement);
}

// The optional bone mask (input port 1, through SetInputConnection): cement where the mask is 0 is leaked (2),
// elsewhere 1; the oracle is the mask itself (its 0 half-space z index >= 27, i.e. ahead of the tip).
TEST(SPHInjectionFilter, BoneMaskDecidesLeakedCement) {
  vtkSmartPointer<vtkImageData> ct = cementsph::imaging::toVtk(cementsph::scene::testing::scaffold());
  auto mask = vtkSmartPointer<vtkImageData>::New();
  mask->CopyStructure(ct);
  mask->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto* m = static_cast<std::uint8_t*>(mask->GetScalarPointer());
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) m[flat(i, j, k)] = k >= 27 ? 0 : 1;
  auto ctSource = vtkSmartPointer<vtkTrivialProducer>::New();
  ctSource->SetOutput(ct);
  auto maskSource = vtkSmartPointer<vtkTrivialProducer>::New();
  maskSource->SetOutput(mask);
  ProgressLog log;
  auto filter = makeFilter(ct, log);
  filter->SetInputConnection(0, ctSource->GetOutputPort());
  filter->SetBoneMaskConnection(maskSource->GetOutputPort());
  filter->Update();
  ASSERT_EQ(filter->GetErrorMessage(), "");
  const auto* l = static_cast<const std::uint8_t*>(filter->GetLabelMapOutput()->GetScalarPointer());
  std::size_t ahead = 0, behind = 0, wrong = 0;
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        const std::uint8_t v = l[flat(i, j, k)];
        if (v == vtkSPHInjectionFilter::NoCement) continue;
        if (k >= 27) {
          ++ahead;
          wrong += v != vtkSPHInjectionFilter::LeakedCement;
        } else {
          ++behind;
          wrong += v != vtkSPHInjectionFilter::Cement;
        }
      }
  EXPECT_EQ(wrong, 0u);
  EXPECT_GT(ahead, 50u); // the cement reaches past the tip's plane
  EXPECT_GT(behind, 50u);
  // A mask on another grid: one line, no run.
  auto small = vtkSmartPointer<vtkImageData>::New();
  small->SetDimensions(20, 40, 40);
  small->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  filter->SetBoneMaskData(small);
  filter->Update();
  EXPECT_NE(filter->GetErrorMessage().find("not on the CT's grid"), std::string::npos) << filter->GetErrorMessage();
  EXPECT_EQ(filter->GetErrorMessage().find('\n'), std::string::npos);
  EXPECT_EQ(filter->GetMetricsJSON(), "");
}

// A particle engine (the equation of state) has no per-voxel fill: the label map is where the simulated CT
// rose by at least k/2 = 1500 HU (cement density at least half rho0). The oracle is that rule applied here to
// the two images voxel by voxel (and the input's own values), plus the tip's voxel holding cement.
TEST(SPHInjectionFilter, ParticleEngineLabelsWhereTheCTRoseByHalfK) {
  vtkSmartPointer<vtkImageData> ct = cementsph::imaging::toVtk(cementsph::scene::testing::scaffold());
  ProgressLog log;
  auto filter = makeFilter(ct, log);
  cementsph::scene::SceneConfig scene = filter->GetScene();
  scene.pressureModel = "equation-of-state";
  filter->SetScene(scene);
  filter->Update();
  ASSERT_EQ(filter->GetErrorMessage(), "");
  ASSERT_EQ(filter->GetCementPointsOutput()->GetPointData()->GetArray("fill_fraction"), nullptr); // particles
  const auto* l = static_cast<const std::uint8_t*>(filter->GetLabelMapOutput()->GetScalarPointer());
  vtkImageData* sim = filter->GetSimulatedCTOutput();
  std::size_t cement = 0, disagree = 0;
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        const bool rose = sim->GetScalarComponentAsDouble(i, j, k, 0) - ct->GetScalarComponentAsDouble(i, j, k, 0) >= 1500.0;
        const std::uint8_t v = l[flat(i, j, k)];
        cement += v == vtkSPHInjectionFilter::Cement;
        disagree += rose != (v == vtkSPHInjectionFilter::Cement) || v == vtkSPHInjectionFilter::LeakedCement;
      }
  EXPECT_EQ(disagree, 0u);
  EXPECT_GT(cement, 100u);
  EXPECT_EQ(l[flat(26, 26, 27)], vtkSPHInjectionFilter::Cement); // half a millimetre ahead of the tip
}

// The label map is the engine's own (the driver's cement_labels.nrrd on the input grid, written by another code
// path: InjectionDriver's labelsOnInputGrid) voxel for voxel, whether the filter takes it from the files'
// image (OutputDirectory set) or maps the region's labels itself (no files). The oracle is the file.
TEST(SPHInjectionFilter, LabelMapIsTheEnginesCementLabelsFile) {
  vtkSmartPointer<vtkImageData> ct = cementsph::imaging::toVtk(cementsph::scene::testing::scaffold());
  ct->SetOrigin(1.0, -2.0, 0.5);
  ProgressLog log;
  auto filter = makeFilter(ct, log);
  filter->SetTipMm(13 + 1.0, 13 - 2.0, 13 + 0.5);
  const auto dir = std::filesystem::path(CEMENTSPH_BINARY_DIR) / "Testing" / "SPHInjectionFilterLabels";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  filter->SetOutputDirectory(dir.string());
  filter->Update();
  ASSERT_EQ(filter->GetErrorMessage(), "");
  const auto file = cementsph::imaging::readVolume((dir / "cement_labels.nrrd").string());
  vtkSmartPointer<vtkImageData> withFiles = vtkSmartPointer<vtkImageData>::New();
  withFiles->DeepCopy(filter->GetLabelMapOutput());
  filter->SetOutputDirectory("");
  filter->Update();
  ASSERT_EQ(filter->GetErrorMessage(), "");
  vtkImageData* withoutFiles = filter->GetLabelMapOutput();
  ASSERT_EQ(file->GetLargestPossibleRegion().GetNumberOfPixels(), std::size_t(withoutFiles->GetNumberOfPoints()));
  const auto* a = static_cast<const std::uint8_t*>(withFiles->GetScalarPointer());
  const auto* b = static_cast<const std::uint8_t*>(withoutFiles->GetScalarPointer());
  const float* f = file->GetBufferPointer();
  std::size_t differ = 0, cement = 0;
  for (vtkIdType i = 0; i < withoutFiles->GetNumberOfPoints(); ++i) {
    differ += float(a[i]) != f[i] || float(b[i]) != f[i];
    cement += f[i] == 1.f;
  }
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(cement, 500u);
}

namespace {
// The figures with the keys that time the machine, not the run, removed (the engines' own end in _wall_s).
nlohmann::json withoutWallTimes(nlohmann::json m) {
  for (const char* key : {"wall_time_s", "real_time_factor", "timing", "provenance"}) m.erase(key);
  for (auto it = m.begin(); it != m.end();) {
    const std::string& key = it.key();
    const bool wall = key.size() > 7 && key.compare(key.size() - 7, 7, "_wall_s") == 0;
    it = wall ? m.erase(it) : std::next(it);
  }
  return m;
}
} // namespace

// The typed result (GetResult) is the run's, not a re-reading of its files. Oracle: the inject driver
// (runInjection) run directly on the same CT (the scaffold's ITK image, not the filter's copy of it) with the
// filter's own scene: every figure but the wall times, the outlet's series sample for sample and the region's
// simulated CT voxel for voxel must be identical (the one driver on the same voxels: to the bit, no tolerance).
TEST(SPHInjectionFilter, TheTypedResultIsTheDriversRunOnTheSameScene) {
  const auto itk = cementsph::scene::testing::scaffold();
  vtkSmartPointer<vtkImageData> ct = cementsph::imaging::toVtk(itk);
  ProgressLog log;
  auto filter = makeFilter(ct, log);
  EXPECT_EQ(filter->GetResult(), nullptr); // before a run
  filter->Update();
  ASSERT_EQ(filter->GetErrorMessage(), "");
  const cementsph::scene::InjectionRunResult* viaFilter = filter->GetResult();
  ASSERT_NE(viaFilter, nullptr);
  EXPECT_EQ(filter->GetSummary(), &viaFilter->summary);
  const cementsph::scene::InjectionRunResult direct = cementsph::scene::runInjection(itk, filter->GetScene(), {});
  EXPECT_EQ(withoutWallTimes(viaFilter->summary.toJson()), withoutWallTimes(direct.summary.toJson()));
  EXPECT_EQ(withoutWallTimes(viaFilter->metrics), withoutWallTimes(direct.metrics));
  EXPECT_EQ(withoutWallTimes(nlohmann::json::parse(filter->GetMetricsJSON())), withoutWallTimes(direct.metrics));
  ASSERT_EQ(viaFilter->tipSeries.size(), direct.tipSeries.size());
  EXPECT_GT(direct.tipSeries.size(), 10u);
  for (std::size_t i = 0; i < direct.tipSeries.size(); ++i) {
    EXPECT_EQ(viaFilter->tipSeries[i].time, direct.tipSeries[i].time) << "sample " << i;
    EXPECT_EQ(viaFilter->tipSeries[i].tipPa, direct.tipSeries[i].tipPa) << "sample " << i;
    EXPECT_EQ(viaFilter->tipSeries[i].cannulaPa, direct.tipSeries[i].cannulaPa) << "sample " << i;
  }
  ASSERT_TRUE(viaFilter->simulatedCt && direct.simulatedCt);
  ASSERT_EQ(viaFilter->simulatedCt->GetLargestPossibleRegion(), direct.simulatedCt->GetLargestPossibleRegion());
  const std::size_t n = direct.simulatedCt->GetLargestPossibleRegion().GetNumberOfPixels();
  std::size_t differ = 0;
  for (std::size_t i = 0; i < n; ++i)
    differ += viaFilter->simulatedCt->GetBufferPointer()[i] != direct.simulatedCt->GetBufferPointer()[i];
  EXPECT_EQ(differ, 0u);
  EXPECT_EQ(viaFilter->particles->GetNumberOfPoints(), direct.particles->GetNumberOfPoints());
  // A failed run leaves no result behind.
  filter->SetTipMm(0.5, 0.5, 13); // in a rod
  filter->Update();
  EXPECT_NE(filter->GetErrorMessage(), "");
  EXPECT_EQ(filter->GetResult(), nullptr);
  EXPECT_EQ(filter->GetSummary(), nullptr);
}

// ProduceImageOutputs off (plan's evaluations): ports 0 and 1 stay empty, and the run is the same. Oracle: the
// same filter's run with image outputs (itself checked against the driver above and against the CT's geometry
// in the tests before): the same figures, series and cement points. Turning it back on reruns and fills them.
TEST(SPHInjectionFilter, WithoutImageOutputsThePortsAreEmptyAndTheRunIsTheSame) {
  vtkSmartPointer<vtkImageData> ct = cementsph::imaging::toVtk(cementsph::scene::testing::scaffold());
  ProgressLog log;
  auto withImages = makeFilter(ct, log);
  withImages->Update();
  ASSERT_EQ(withImages->GetErrorMessage(), "");
  auto pointsOnly = makeFilter(ct, log);
  EXPECT_TRUE(pointsOnly->GetProduceImageOutputs()); // on by default
  pointsOnly->ProduceImageOutputsOff();
  pointsOnly->Update();
  ASSERT_EQ(pointsOnly->GetErrorMessage(), "");
  EXPECT_EQ(pointsOnly->GetSimulatedCTOutput()->GetNumberOfPoints(), 0);
  EXPECT_EQ(pointsOnly->GetLabelMapOutput()->GetNumberOfPoints(), 0);
  const auto* a = withImages->GetResult();
  const auto* b = pointsOnly->GetResult();
  ASSERT_TRUE(a && b);
  EXPECT_EQ(withoutWallTimes(b->metrics), withoutWallTimes(a->metrics));
  ASSERT_EQ(b->tipSeries.size(), a->tipSeries.size());
  for (std::size_t i = 0; i < a->tipSeries.size(); ++i) EXPECT_EQ(b->tipSeries[i].tipPa, a->tipSeries[i].tipPa) << i;
  vtkPolyData* pa = withImages->GetCementPointsOutput();
  vtkPolyData* pb = pointsOnly->GetCementPointsOutput();
  ASSERT_EQ(pb->GetNumberOfPoints(), pa->GetNumberOfPoints());
  EXPECT_GT(pb->GetNumberOfPoints(), 0);
  for (vtkIdType i = 0; i < pa->GetNumberOfPoints(); ++i)
    for (int axis = 0; axis < 3; ++axis) ASSERT_EQ(pb->GetPoint(i)[axis], pa->GetPoint(i)[axis]) << "point " << i;
  pointsOnly->ProduceImageOutputsOn();
  pointsOnly->Update();
  EXPECT_EQ(pointsOnly->GetSimulatedCTOutput()->GetNumberOfPoints(), ct->GetNumberOfPoints());
  EXPECT_EQ(pointsOnly->GetLabelMapOutput()->GetNumberOfPoints(), ct->GetNumberOfPoints());
}

// The filter keeps its copy of the input between runs (a plan's dozens of runs on one CT) only while the input is
// unchanged: after the input's voxels change (and say so, Modified), the run sees the new CT. Oracle: the
// scaffold's geometry; the pore at the tip filled with 1000 HU is solid, and a tip in solid is refused.
TEST(SPHInjectionFilter, AChangedInputIsCopiedAgain) {
  vtkSmartPointer<vtkImageData> ct = cementsph::imaging::toVtk(cementsph::scene::testing::scaffold());
  ProgressLog log;
  auto filter = makeFilter(ct, log);
  filter->ProduceImageOutputsOff();
  filter->Update();
  ASSERT_EQ(filter->GetErrorMessage(), "");
  for (int k = 24; k <= 28; ++k)
    for (int j = 24; j <= 28; ++j)
      for (int i = 24; i <= 28; ++i) ct->SetScalarComponentFromDouble(i, j, k, 0, 1000.0); // around the tip
  ct->Modified();
  filter->Update();
  EXPECT_NE(filter->GetErrorMessage().find("lies in solid"), std::string::npos) << filter->GetErrorMessage();
}
