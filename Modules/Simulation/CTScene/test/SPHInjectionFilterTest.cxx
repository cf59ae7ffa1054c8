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
