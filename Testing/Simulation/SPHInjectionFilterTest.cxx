// vtkSPHInjectionFilter in a VTK pipeline: the scaffold CT in (vtkImageData), particles and the simulated CT
// out, setters, progress events, abort, and errors reported without a VTK error print.
#include "ScaffoldCT.h"

#include "cementsph/imaging/ItkVtkBridge.h"
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
  filter->SetInputDataObject(0, ct);
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
  for (const char* a : {"velocity_m_per_s", "density_kg_per_m3", "pressure_pa", "age_s"})
    EXPECT_NE(particles->GetPointData()->GetArray(a), nullptr) << a;
  vtkImageData* sim = filter->GetSimulatedCTOutput();
  ASSERT_NE(sim, nullptr);
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
