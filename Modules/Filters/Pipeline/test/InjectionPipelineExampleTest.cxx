// Examples/cpp/InjectionPipeline.cxx run as a user would, on the bundled foam phantom (1 ml, the paper scene,
// the phantom's tip and post-injection CT), its surface checked against oracles independent of the code:
//  * the cement's isosurface encloses the injected volume (flow x time, 0.05 ml/s x 20 s): the cement fills
//    pores of porosity 1 and the struts among it are holes in the label map, so the surface encloses the
//    cement alone. Within 5 % (the 0.5-isosurface of a 0/1 map cuts the corners of the convoluted front and
//    of the strut holes; measured 0.983 ml);
//  * the label map (printed) holds flow x time in voxels at least half filled, pores of porosity 1, within 2 %
//    (the half-filled front counted at 0.5: 9009 voxels = 0.995 ml measured);
//  * no leak: the surface lies inside the foam block (truth.json's block_min_mm / block_max_mm), so none of the
//    cement is in the air the bone mask (HU >= -500) leaves out: 0 leaked voxels;
//  * the phantom's post scan was made by this model with this plan (truth.json), so once registered its
//    cement surface agrees with the simulated one within half a voxel (0.235 mm) on average (measured 0.025 mm).
#include "ProgramRun.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <vtkDataArray.h>
#include <vtkMassProperties.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>

#include <filesystem>
#include <fstream>
#include <regex>

TEST(InjectionPipelineExample, TheSurfaceEnclosesTheInjectedVolume) {
  const std::string data = CEMENTSPH_TEST_DATA_DIR;
  const auto out = std::filesystem::path(CEMENTSPH_BINARY_DIR) / "Testing" / "InjectionPipelineExample";
  std::filesystem::create_directories(out);
  const auto surfacePath = out / "cement.vtp";
  std::filesystem::remove(surfacePath);
  const auto run = cementsph::testing::runProgram(
      EXAMPLE_EXECUTABLE, {data + "/foam-phantom/pre.nrrd", data + "/scenes/paper-1ml.json", "22.325", "21.855", "21.75",
                           surfacePath.string(), data + "/foam-phantom/post.nrrd"});
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NE(run.out.find("injected 1 ml"), std::string::npos) << run.out;

  std::ifstream truthFile(data + "/foam-phantom/truth.json");
  const nlohmann::json truth = nlohmann::json::parse(truthFile);
  const double injectedMl = truth["injection"]["flow_rate_ml_per_s"].get<double>() * 20.0; // the scene's 20 s

  std::smatch counts;
  ASSERT_TRUE(std::regex_search(run.out, counts, std::regex("label map: ([0-9]+) cement voxels, ([0-9]+) leaked"))) << run.out;
  const double voxelMl = truth["foam"]["spacing_mm"][0].get<double>() * truth["foam"]["spacing_mm"][1].get<double>() *
                         truth["foam"]["spacing_mm"][2].get<double>() * 1e-3;
  EXPECT_NEAR(std::stod(counts[1]) * voxelMl / injectedMl, 1.0, 0.02);
  EXPECT_EQ(counts[2], "0");

  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(surfacePath.string().c_str());
  reader->Update();
  vtkPolyData* surface = reader->GetOutput();
  ASSERT_GT(surface->GetNumberOfCells(), 1000);
  vtkNew<vtkMassProperties> mass;
  mass->SetInputData(surface);
  mass->Update();
  const double enclosedMl = mass->GetVolume() * 1e-3;
  std::printf("isosurface encloses %.4f ml against %.4f ml\n", enclosedMl, injectedMl);
  EXPECT_NEAR(enclosedMl / injectedMl, 1.0, 0.05);

  double bounds[6];
  surface->GetBounds(bounds);
  for (int a = 0; a < 3; ++a) {
    EXPECT_GT(bounds[2 * a], truth["foam"]["block_min_mm"][a].get<double>()) << a;
    EXPECT_LT(bounds[2 * a + 1], truth["foam"]["block_max_mm"][a].get<double>()) << a;
  }

  vtkDataArray* distance = surface->GetPointData()->GetArray("DistanceToOtherSurface_mm");
  ASSERT_NE(distance, nullptr);
  double sum = 0;
  for (vtkIdType i = 0; i < distance->GetNumberOfTuples(); ++i) sum += distance->GetTuple1(i);
  const double mean = sum / double(distance->GetNumberOfTuples());
  std::printf("mean distance to the registered post scan's cement: %.4f mm\n", mean);
  EXPECT_LT(mean, 0.235);
}
