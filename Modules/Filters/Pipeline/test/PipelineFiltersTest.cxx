// The pipeline filters (Modules/Filters/Pipeline) and the injection filter joined by SetInputConnection, each
// against an oracle that does not come from the code under test:
//  * the reader: the geometry a volume was written with (origin, spacing, an oblique direction), exactly;
//  * the surface distance: two concentric spheres of radii 5 and 6 mm are 1 mm apart everywhere (within the
//    tessellation's sag, r (1 - cos(pi / n)) < 0.003 mm at 100 segments: 0.01 mm);
//  * registration: the phantom against a copy of itself moved by a known translation: that translation within
//    0.05 mm (a tenth of a voxel);
//  * the label isosurface of a ball in a flipped-axes CT: centred on the ball's physical centre (0.01 mm);
//  * reader -> injection on the foam phantom: the cement label map holds flow x time (0.05 ml/s x 20 s = 1 ml)
//    in voxels at least half filled, pores of porosity 1 (pore-resolved bone), within 2 % (the half-filled
//    front is counted at the 0.5 threshold: 9009 voxels of 0.11045 mm^3 = 0.995 ml measured).
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/pipeline/vtkAffineRegistrationFilter.h"
#include "cementsph/pipeline/vtkCementSPHImageReader.h"
#include "cementsph/pipeline/vtkLabelIsosurfaceFilter.h"
#include "cementsph/pipeline/vtkSurfaceDistanceFilter.h"
#include "vtkSPHInjectionFilter.h"

#include <gtest/gtest.h>
#include <vtkImageChangeInformation.h>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkMatrix4x4.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSphereSource.h>
#include <vtkTrivialProducer.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>

namespace {
const std::string kData = CEMENTSPH_TEST_DATA_DIR;

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::path(CEMENTSPH_BINARY_DIR) / "Testing" / "PipelineFilters";
  std::filesystem::create_directories(dir);
  return dir / name;
}
} // namespace

TEST(PipelineFilters, ReaderKeepsTheFilesGeometry) {
  vtkNew<vtkImageData> written;
  written->SetDimensions(5, 6, 7);
  written->SetOrigin(-12.5, 3.25, 100.0);
  written->SetSpacing(0.7, 0.8, 1.5);
  const double c = std::cos(0.3), s = std::sin(0.3);
  written->SetDirectionMatrix(c, -s, 0, s, c, 0, 0, 0, 1); // oblique: 0.3 rad about z
  written->AllocateScalars(VTK_FLOAT, 1);
  auto* v = static_cast<float*>(written->GetScalarPointer());
  for (vtkIdType i = 0; i < written->GetNumberOfPoints(); ++i) v[i] = float(i) - 100.f;
  const auto path = scratch("oblique.nrrd");
  cementsph::imaging::writeVolume(cementsph::imaging::imageFromVtk(written), path.string());

  vtkNew<vtkCementSPHImageReader> reader;
  reader->SetFileName(path.string());
  reader->Update();
  ASSERT_EQ(reader->GetErrorMessage(), "");
  vtkImageData* read = reader->GetOutput();
  int dims[3];
  read->GetDimensions(dims);
  EXPECT_EQ(dims[0], 5);
  EXPECT_EQ(dims[1], 6);
  EXPECT_EQ(dims[2], 7);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(read->GetOrigin()[a], written->GetOrigin()[a], 1e-9);
    EXPECT_NEAR(read->GetSpacing()[a], written->GetSpacing()[a], 1e-9);
    for (int b = 0; b < 3; ++b)
      EXPECT_NEAR(read->GetDirectionMatrix()->GetElement(a, b), written->GetDirectionMatrix()->GetElement(a, b), 1e-9);
  }
  EXPECT_FLOAT_EQ(read->GetScalarComponentAsFloat(4, 5, 6, 0), float(4 + 5 * 5 + 30 * 6) - 100.f); // i + 5 j + 30 k

  reader->SetFileName((std::filesystem::path(kData) / "no-such-volume.nrrd").string());
  reader->Update();
  EXPECT_NE(reader->GetErrorMessage(), "");
  EXPECT_EQ(reader->GetErrorMessage().find('\n'), std::string::npos) << reader->GetErrorMessage();
  EXPECT_EQ(reader->GetOutput()->GetNumberOfPoints(), 0);
  EXPECT_THROW(reader->RethrowIfFailed(), std::exception);
}

TEST(PipelineFilters, ConcentricSpheresAreTheirRadiiApart) {
  vtkNew<vtkSphereSource> inner, outer;
  inner->SetRadius(5.0);
  outer->SetRadius(6.0);
  for (auto* sphere : {inner.Get(), outer.Get()}) {
    sphere->SetCenter(1.0, -2.0, 3.0);
    sphere->SetThetaResolution(100);
    sphere->SetPhiResolution(100);
  }
  vtkNew<vtkSurfaceDistanceFilter> distance;
  distance->SetInputConnection(inner->GetOutputPort());
  distance->SetReferenceConnection(outer->GetOutputPort());
  distance->Update();
  ASSERT_EQ(distance->GetErrorMessage(), "");
  EXPECT_NEAR(distance->GetErrorMm(), 1.0, 0.01);
  EXPECT_NEAR(distance->GetMeanAToBMm(), 1.0, 0.01);
  EXPECT_NEAR(distance->GetMeanBToAMm(), 1.0, 0.01);
  EXPECT_NEAR(distance->GetHausdorffMm(), 1.0, 0.01);
  vtkDataArray* d = distance->GetOutput()->GetPointData()->GetArray("DistanceToOtherSurface_mm");
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->GetNumberOfTuples(), inner->GetOutput()->GetNumberOfPoints());
  // The input surface itself is left as it was.
  EXPECT_EQ(inner->GetOutput()->GetPointData()->GetArray("DistanceToOtherSurface_mm"), nullptr);
}

TEST(PipelineFilters, RegistrationRecoversAKnownTranslation) {
  vtkNew<vtkCementSPHImageReader> pre;
  pre->SetFileName(kData + "/foam-phantom/pre.nrrd");
  // The same scan, its origin moved by t: a fixed point x is the moving image's point x + t.
  const double t[3] = {1.0, -0.5, 0.7};
  vtkNew<vtkImageChangeInformation> moved;
  moved->SetInputConnection(pre->GetOutputPort());
  moved->SetOriginTranslation(t[0], t[1], t[2]);
  vtkNew<vtkAffineRegistrationFilter> registration;
  registration->SetFixedConnection(pre->GetOutputPort());
  registration->SetMovingConnection(moved->GetOutputPort());
  registration->Update();
  ASSERT_EQ(registration->GetErrorMessage(), "");
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(registration->GetMatrix()->GetElement(a, 3), t[a], 0.05) << a;
    for (int b = 0; b < 3; ++b) EXPECT_NEAR(registration->GetMatrix()->GetElement(a, b), a == b ? 1.0 : 0.0, 0.01);
  }
  // The output lies on the fixed grid.
  int dims[3];
  registration->GetOutput()->GetDimensions(dims);
  EXPECT_EQ(dims[0], 94);
  EXPECT_EQ(dims[2], 88);
}

TEST(PipelineFilters, InjectionLabelMapOnThePhantomHoldsFlowTimesTime) {
  vtkNew<vtkCementSPHImageReader> reader;
  reader->SetFileName(kData + "/foam-phantom/pre.nrrd");
  vtkNew<vtkSPHInjectionFilter> injection;
  injection->SetInputConnection(reader->GetOutputPort());
  injection->SetScene(cementsph::scene::loadSceneFile(kData + "/scenes/paper-1ml.json", {"tip_mm=[22.325,21.855,21.75]"}));
  injection->Update();
  ASSERT_EQ(injection->GetErrorMessage(), "");
  vtkImageData* labels = injection->GetLabelMapOutput();
  int dims[3];
  labels->GetDimensions(dims);
  EXPECT_EQ(dims[0], 94); // the input's grid (the issue: 94 x 94 x 88, not the 40 mm region)
  EXPECT_EQ(dims[1], 94);
  EXPECT_EQ(dims[2], 88);
  const auto* l = static_cast<const std::uint8_t*>(labels->GetScalarPointer());
  std::size_t cement = 0, leaked = 0;
  for (vtkIdType i = 0; i < labels->GetNumberOfPoints(); ++i) {
    cement += l[i] == vtkSPHInjectionFilter::Cement;
    leaked += l[i] == vtkSPHInjectionFilter::LeakedCement;
  }
  const double voxelMl = 0.47 * 0.47 * 0.5 * 1e-3, oracleMl = 0.05 * 20.0;
  std::printf("phantom: %zu cement voxels = %.4f ml against %.4f ml\n", cement, double(cement) * voxelMl, oracleMl);
  EXPECT_NEAR(double(cement) * voxelMl / oracleMl, 1.0, 0.02);
  EXPECT_EQ(leaked, 0u); // pore-resolved bone and no mask: leakage is not assessed
}

// A ball of labels in a CT whose x and y axes are flipped (direction diag(-1, -1, 1), as a RAS-stored scan read
// in LPS): the surface's centre is the ball's physical centre, computed here from the grid's geometry (within
// 0.01 mm: a symmetric staircase about it), and its bounds span the ball's 6 mm radius within half a voxel.
TEST(PipelineFilters, LabelIsosurfaceHonoursTheDirectionMatrix) {
  vtkNew<vtkImageData> labels;
  labels->SetDimensions(30, 30, 30);
  labels->SetSpacing(0.5, 0.5, 0.5);
  labels->SetOrigin(40.0, 20.0, -5.0);
  labels->SetDirectionMatrix(-1, 0, 0, 0, -1, 0, 0, 0, 1);
  labels->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto* l = static_cast<std::uint8_t*>(labels->GetScalarPointer());
  for (int k = 0; k < 30; ++k)
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 30; ++i) {
        const double r = 0.5 * std::sqrt((i - 14.5) * (i - 14.5) + (j - 14.5) * (j - 14.5) + (k - 14.5) * (k - 14.5));
        l[i + 30 * (j + 30 * k)] = r <= 6.0 ? (k < 15 ? 1 : 2) : 0; // cement and leaked cement: both inside
      }
  // Index (14.5, 14.5, 14.5) in physical space: origin + direction * spacing * index.
  const double centre[3] = {40.0 - 0.5 * 14.5, 20.0 - 0.5 * 14.5, -5.0 + 0.5 * 14.5};
  vtkNew<vtkTrivialProducer> source;
  source->SetOutput(labels);
  vtkNew<vtkLabelIsosurfaceFilter> surface;
  surface->SetInputConnection(source->GetOutputPort());
  surface->Update();
  double bounds[6];
  surface->GetOutput()->GetBounds(bounds);
  ASSERT_GT(surface->GetOutput()->GetNumberOfCells(), 100);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(0.5 * (bounds[2 * a] + bounds[2 * a + 1]), centre[a], 0.01) << a;
    EXPECT_NEAR(0.5 * (bounds[2 * a + 1] - bounds[2 * a]), 6.0, 0.25) << a;
  }
}
