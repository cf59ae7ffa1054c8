// The paper's pictures (Basafa et al. 2013, Figs. 7, 10, 11) on a machine without a display: each has the
// requested size, is not blank, matches a stored baseline, and a changed input does not match it.
#include "RenderingTestSupport.h"

#include "cementsph/rendering/CementSlices.h"
#include "cementsph/rendering/CementSurface.h"
#include "cementsph/rendering/ImageCompare.h"
#include "cementsph/rendering/SliceComparison.h"
#include "cementsph/rendering/SurfaceComparison.h"
#include "cementsph/rendering/TipPressurePlot.h"

#include <gtest/gtest.h>

#include <vtkDoubleArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkSphereSource.h>

#include <array>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <vector>

using namespace cementsph::rendering;
using cementsph::rendering::test::expectMatchesBaseline;
using cementsph::rendering::test::forgetDisplay;
using cementsph::rendering::test::kBaselineDir;
using cementsph::rendering::test::scratchFolder;
using cementsph::rendering::test::summarisePng;

namespace {


// GL pictures (surfaces, plot): fraction of visibly changed pixels allowed (imageDifference). Re-rendering
// on the same stack gives 0; 1e-3 of a 1500 x 560 picture is 840 pixels, room for shading differences of
// another Mesa at silhouette edges. Moving the simulated surface by 1.5 mm changes far more (see below).
constexpr double kGlTolerance = 1e-3;

void expectNotBlank(const std::filesystem::path& png, int width, int height, std::size_t minColours) {
  const auto s = summarisePng(png);
  EXPECT_EQ(s.width, width);
  EXPECT_EQ(s.height, height);
  EXPECT_GT(s.distinctColours, minColours) << "hardly any colours: blank image?";
  EXPECT_GT(s.nonWhiteFraction, 0.02) << "almost all background";
}

double secondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// --- Fig. 7: two spheres like Data/compare-example (CT cement r = 5.5 mm, simulated r = 6 mm shifted). ---

vtkSmartPointer<vtkPolyData> sphere(double radius, double cx) {
  vtkNew<vtkSphereSource> s;
  s->SetRadius(radius);
  s->SetCenter(cx, 0.0, 0.0);
  s->SetThetaResolution(48);
  s->SetPhiResolution(32);
  s->Update();
  vtkSmartPointer<vtkPolyData> out = s->GetOutput();
  return out;
}

// Distance of each vertex of `surface` to the sphere (centre (cx,0,0), radius r): | |p - c| - r |, the
// quantity cementsph::surfacemetrics::compareSurfaces stores, computed exactly here.
void addDistanceToSphere(vtkPolyData* surface, double r, double cx) {
  vtkNew<vtkDoubleArray> d;
  d->SetName("DistanceToOtherSurface_mm");
  for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i) {
    double p[3];
    surface->GetPoint(i, p);
    d->InsertNextValue(std::abs(std::hypot(p[0] - cx, p[1], p[2]) - r));
  }
  surface->GetPointData()->AddArray(d);
}

void renderSpheres(double simulatedOffsetMm, const std::filesystem::path& png) {
  auto ct = sphere(5.5, 0.0);
  auto sim = sphere(6.0, simulatedOffsetMm);
  addDistanceToSphere(sim, 5.5, 0.0);
  SurfaceComparisonOptions options;
  options.maxDistanceMm = 2.0;
  renderSurfaceComparison(ct, sim, png, options);
}

// --- Fig. 11: a bone cylinder (300 HU) with a cement sphere (2500 HU). ---

vtkSmartPointer<vtkImageData> phantom(double cementCx) {
  auto v = vtkSmartPointer<vtkImageData>::New();
  v->SetDimensions(48, 40, 50);
  v->SetSpacing(0.5, 0.5, 0.5);
  v->SetOrigin(-12.0, -10.0, -12.0);
  v->AllocateScalars(VTK_FLOAT, 1);
  auto* p = static_cast<float*>(v->GetScalarPointer());
  for (int k = 0; k < 50; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 48; ++i) {
        const double x = -12.0 + 0.5 * i, y = -10.0 + 0.5 * j, z = -12.0 + 0.5 * k;
        float hu = -1000.0f;
        if (std::hypot(x, y) < 9.0) hu = 300.0f + 40.0f * static_cast<float>(std::sin(x) * std::cos(1.3 * y));
        if (std::hypot(x - cementCx, y - 2.0, z) < 6.0) hu = 2500.0f;
        p[(static_cast<std::size_t>(k) * 40 + j) * 48 + i] = hu;
      }
  return v;
}

// --- Fig. 10: a pressure curve that rises and then levels off. ---

void writePressureCsv(const std::filesystem::path& csv, double scale) {
  std::ofstream out(csv);
  out << "time_s,pressure_pa,pressure_minus_baseline_pa\n";
  for (int i = 0; i <= 100; ++i) {
    const double t = 0.05 * i;
    const double p = scale * (1.0e5 * (1.0 - std::exp(-t / 0.8)) + 6.0e3 * std::sin(5.0 * t));
    out << t << "," << (p + 2.0e4) << "," << p << "\n";
  }
}

} // namespace

TEST(SurfaceComparisonRegression, MatchesBaseline) {
  forgetDisplay();
  const auto png = scratchFolder() / "surfaces.png";
  const auto t = std::chrono::steady_clock::now();
  renderSpheres(0.8, png);
  std::cout << "renderSurfaceComparison took " << secondsSince(t) << " s\n";
  expectNotBlank(png, 1500, 560, 50);
  expectMatchesBaseline(png, "surface_comparison.png", kGlTolerance);
}

TEST(SurfaceComparisonRegression, ShiftedSimulationDoesNotMatchBaseline) {
  forgetDisplay();
  const auto png = scratchFolder() / "shifted.png";
  renderSpheres(2.3, png);
  const double difference = imageDifference(png, kBaselineDir / "surface_comparison.png");
  std::cout << "difference of a 1.5 mm shifted simulation from the baseline: " << difference << "\n";
  EXPECT_GT(difference, 5.0 * kGlTolerance);
}

TEST(SurfaceComparison, RejectsMissingInputsAndLeavesNoFile) {
  forgetDisplay();
  const auto dir = scratchFolder();
  auto ct = sphere(5.5, 0.0);
  auto sim = sphere(6.0, 0.8); // no distance array
  EXPECT_THROW(renderSurfaceComparison(ct, sim, dir / "a.png"), std::invalid_argument);
  EXPECT_THROW(renderSurfaceComparison(nullptr, ct, dir / "b.png"), std::invalid_argument);
  vtkNew<vtkPolyData> empty;
  addDistanceToSphere(sim, 5.5, 0.0);
  EXPECT_THROW(renderSurfaceComparison(empty, sim, dir / "c.png"), std::invalid_argument);
  EXPECT_THROW(renderSurfaceComparison(ct, sim, dir / "missing" / "d.png"), std::runtime_error);
  EXPECT_TRUE(std::filesystem::directory_iterator(dir) == std::filesystem::directory_iterator());
}

TEST(SliceComparison, PositionsAreEvery5mmThroughTheCement) {
  auto post = phantom(0.0);
  const auto z = slicePositionsMm(post, nullptr, 5.0);
  // Cement voxels span z in [-5.5, 5.5] (sphere r = 6 on a 0.5 mm grid): 3 slices at -5, 0, 5.
  ASSERT_EQ(z.size(), 3u);
  EXPECT_NEAR(z[0], -5.0, 1e-9);
  EXPECT_NEAR(z[1], 0.0, 1e-9);
  EXPECT_NEAR(z[2], 5.0, 1e-9);
}

// No GL is involved, so the pixels must be identical to the baseline's.
TEST(SliceComparisonRegression, MatchesBaselineExactly) {
  forgetDisplay();
  const auto png = scratchFolder() / "slices.png";
  const auto t = std::chrono::steady_clock::now();
  // The bare panels (the labels are LabelledSlicesTest's): their pixels are the baseline's.
  SliceComparisonOptions bare;
  bare.annotate = false;
  renderSliceComparison(phantom(0.0), phantom(1.5), png, 5.0, bare);
  std::cout << "renderSliceComparison took " << secondsSince(t) << " s\n";
  // 48 voxels x scale 4 = 192 px panels, 3 slices, 2 rows, 6 px gaps.
  expectNotBlank(png, 6 + 3 * (192 + 6), 6 + 2 * (160 + 6), 8); // a few grey levels: air, bone, cement
  expectMatchesBaseline(png, "slice_comparison.png", 0.0);
  if (!HasFatalFailure() && std::getenv("CEMENTSPH_UPDATE_BASELINES") == nullptr) {
    EXPECT_EQ(meanAbsoluteDifference(png, kBaselineDir / "slice_comparison.png"), 0.0);
  }
}

TEST(SliceComparisonRegression, DifferentSimulationDoesNotMatchBaseline) {
  const auto png = scratchFolder() / "slices.png";
  SliceComparisonOptions bare;
  bare.annotate = false;
  renderSliceComparison(phantom(0.0), phantom(-1.5), png, 5.0, bare);
  const double difference = imageDifference(png, kBaselineDir / "slice_comparison.png");
  std::cout << "difference of a changed simulation from the baseline: " << difference << "\n";
  EXPECT_GT(difference, 0.005);
}

TEST(SliceComparison, PostOnlyGivesOneRowAndBadInputsThrow) {
  const auto dir = scratchFolder();
  SliceComparisonOptions bare;
  bare.annotate = false; // the panels alone: one row of 160 px
  renderSliceComparison(phantom(0.0), nullptr, dir / "post.png", 5.0, bare);
  const auto s = summarisePng(dir / "post.png");
  EXPECT_EQ(s.height, 6 + 160 + 6);
  EXPECT_THROW(renderSliceComparison(phantom(0.0), nullptr, dir / "x.png", 0.0), std::invalid_argument);
  EXPECT_THROW(renderSliceComparison(nullptr, nullptr, dir / "x.png"), std::invalid_argument);
  SliceComparisonOptions noCement;
  noCement.cementThresholdHU = 5000.0;
  EXPECT_THROW(renderSliceComparison(phantom(0.0), nullptr, dir / "x.png", 5.0, noCement), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

TEST(TipPressurePlotRegression, MatchesBaseline) {
  forgetDisplay();
  const auto dir = scratchFolder();
  writePressureCsv(dir / "tip.csv", 1.0);
  const auto t = std::chrono::steady_clock::now();
  writeTipPressurePlot(dir / "tip.csv", dir / "tip.png");
  std::cout << "writeTipPressurePlot took " << secondsSince(t) << " s\n";
  expectNotBlank(dir / "tip.png", 900, 650, 20);
  expectMatchesBaseline(dir / "tip.png", "tip_pressure.png", 2e-4);
}

TEST(TipPressurePlotRegression, DifferentCurveDoesNotMatchBaseline) {
  forgetDisplay();
  const auto dir = scratchFolder();
  writePressureCsv(dir / "tip.csv", 0.6);
  writeTipPressurePlot(dir / "tip.csv", dir / "tip.png");
  EXPECT_GT(imageDifference(dir / "tip.png", kBaselineDir / "tip_pressure.png"), 1e-3);
}

TEST(TipPressurePlot, BadCsvThrowsAndLeavesNoPicture) {
  forgetDisplay();
  const auto dir = scratchFolder();
  {
    std::ofstream(dir / "header.csv") << "t,p,q\n0,1,2\n";
    std::ofstream(dir / "nan.csv") << "time_s,pressure_pa,pressure_minus_baseline_pa\n0,1,2\n0.1,abc,2\n";
    std::ofstream(dir / "empty.csv") << "time_s,pressure_pa,pressure_minus_baseline_pa\n";
  }
  for (const char* name : {"header.csv", "nan.csv", "empty.csv", "absent.csv"})
    EXPECT_THROW(writeTipPressurePlot(dir / name, dir / "out.png"), std::runtime_error) << name;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.png"));
  const auto series = [&] {
    std::ofstream(dir / "ok.csv") << "time_s,pressure_pa,pressure_minus_baseline_pa\n0,100,0\n\n1,300,200\n";
    return readTipPressureCsv(dir / "ok.csv");
  }();
  ASSERT_EQ(series.timeS.size(), 2u);
  EXPECT_DOUBLE_EQ(series.pressureMinusBaselinePa[1], 200.0);
}

TEST(InjectionPressurePlot, ReadsTheSyringeColumnsAndDrawsThem) {
  forgetDisplay();
  const auto dir = scratchFolder();
  // The five columns inject writes: tip, baseline-free tip, cannula drop, syringe (= cannula + tip).
  {
    std::ofstream out(dir / "five.csv");
    out.precision(17);
    out << "time_s,pressure_pa,pressure_minus_baseline_pa,cannula_pressure_drop_pa,injection_pressure_pa\n";
    for (int i = 0; i <= 100; ++i) {
      const double t = 0.2 * i, tip = 8000.0 * (1.0 - std::exp(-t)), cannula = 5.6e5 + 100.0 * t;
      out << t << "," << tip << "," << tip << "," << cannula << "," << tip + cannula << "\n";
    }
  }
  const TipPressureSeries s = readTipPressureCsv(dir / "five.csv");
  ASSERT_EQ(s.injectionPa.size(), 101u);
  EXPECT_NEAR(s.cannulaPa[50], 5.6e5 + 1000.0, 1e-6);
  EXPECT_NEAR(s.injectionPa[100] - s.cannulaPa[100], 8000.0 * (1.0 - std::exp(-20.0)), 1e-6);
  writeInjectionPressurePlot(dir / "five.csv", dir / "injection.png");
  expectNotBlank(dir / "injection.png", 900, 650, 20);
  // A three-column CSV (the paper's model without a cannula column) has no syringe pressure to draw.
  writePressureCsv(dir / "three.csv", 1.0);
  EXPECT_TRUE(readTipPressureCsv(dir / "three.csv").injectionPa.empty());
  EXPECT_THROW(writeInjectionPressurePlot(dir / "three.csv", dir / "none.png"), std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(dir / "none.png"));
}

TEST(CementSlices, GreyIsTheBoneWindowBlueIsCementRedIsLeak) {
  // A 20^3 grid of 1 mm: 300 HU everywhere (the bone window's level: mid grey 127.5), a cement block (label 1)
  // in x < 10 and one leaked voxel column (label 2) at x = 15, y = 10 through all z. Slices through (15, 10, 10).
  auto ct = vtkSmartPointer<vtkImageData>::New(), labels = vtkSmartPointer<vtkImageData>::New();
  for (auto* img : {ct.Get(), labels.Get()}) {
    img->SetDimensions(20, 20, 20);
    img->SetSpacing(1, 1, 1);
    img->SetOrigin(0, 0, 0);
  }
  ct->AllocateScalars(VTK_FLOAT, 1);
  labels->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) {
        ct->SetScalarComponentFromDouble(i, j, k, 0, 300.0);
        labels->SetScalarComponentFromDouble(i, j, k, 0, i < 10 ? 1 : (i == 15 && j == 10) ? 2 : 0);
      }
  const auto dir = scratchFolder();
  CementSlicesOptions o;
  o.pixelsPerPanel = 200; // 10 pixels per voxel
  o.annotate = false;     // the panels alone, 8 px apart (the labels are LabelledSlicesTest's)
  writeCementSlices(ct, labels, {15, 10, 10}, dir / "slices.png", o);
  auto reader = vtkSmartPointer<vtkPNGReader>::New();
  reader->SetFileName((dir / "slices.png").string().c_str());
  reader->Update();
  vtkImageData* png = reader->GetOutput();
  int dims[3];
  png->GetDimensions(dims);
  EXPECT_EQ(dims[0], 3 * 200 + 2 * 8);
  EXPECT_EQ(dims[1], 200);
  auto rgb = [&](int x, int y) {
    return std::array<int, 3>{int(png->GetScalarComponentAsDouble(x, y, 0, 0)), int(png->GetScalarComponentAsDouble(x, y, 0, 1)),
                              int(png->GetScalarComponentAsDouble(x, y, 0, 2))};
  };
  // Axial panel (x to the right, y down): voxel (15, 10) is pixels 150..159 across and rows 100..109 from the
  // top, that is rows 90..99 of the image's bottom-up rows.
  EXPECT_EQ(rgb(155, 95), (std::array<int, 3>{230, 20, 20}));                       // leaked: red
  const double grey = (300.0 - (300.0 - 750.0)) / 1500.0 * 255.0;                   // 127.5: the level
  const int g = int(std::lround(grey));
  EXPECT_EQ(rgb(185, 95), (std::array<int, 3>{g, g, g}));                           // no cement: the window's grey
  const auto blue = rgb(50, 95);                                                    // cement in bone: half blue
  EXPECT_EQ(blue[2], int(std::lround(0.5 * grey + 0.5 * 255)));
  EXPECT_EQ(blue[0], int(std::lround(0.5 * grey + 0.5 * 40)));
  EXPECT_THROW(writeCementSlices(ct, labels, {50, 10, 10}, dir / "outside.png"), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir / "outside.png"));
}

// --- The cement surface from a label map (issue 10: leaks red on the surface picture). ---

namespace {

// 30 x 20 x 20 voxels of 1 mm at the origin: cement in bone (1) in i 3..12, j 5..14, k 5..14; a leak (2) in
// i 20..24, j 8..11, k 12..15, apart from it (nothing hides it from the camera at -y).
vtkSmartPointer<vtkImageData> cementLabels(bool withLeak) {
  auto labels = vtkSmartPointer<vtkImageData>::New();
  labels->SetDimensions(30, 20, 20);
  labels->SetSpacing(1, 1, 1);
  labels->SetOrigin(0, 0, 0);
  labels->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 30; ++i) {
        const bool bone = i >= 3 && i <= 12 && j >= 5 && j <= 14 && k >= 5 && k <= 14;
        const bool leak = withLeak && i >= 20 && i <= 24 && j >= 8 && j <= 11 && k >= 12 && k <= 15;
        labels->SetScalarComponentFromDouble(i, j, k, 0, bone ? 1 : leak ? 2 : 0);
      }
  return labels;
}

struct Pixels {
  std::vector<std::array<int, 2>> red, blue;
};

Pixels classify(const std::filesystem::path& png) {
  auto reader = vtkSmartPointer<vtkPNGReader>::New();
  reader->SetFileName(png.string().c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  int dims[3];
  image->GetDimensions(dims);
  Pixels p;
  for (int y = 0; y < dims[1]; ++y)
    for (int x = 0; x < dims[0]; ++x) {
      const double r = image->GetScalarComponentAsDouble(x, y, 0, 0), g = image->GetScalarComponentAsDouble(x, y, 0, 1),
                   b = image->GetScalarComponentAsDouble(x, y, 0, 2);
      if (r > 120 && r > 2 * g && r > 2 * b) p.red.push_back({x, y});
      if (b > 120 && b > 1.3 * r && b > 1.3 * g) p.blue.push_back({x, y});
    }
  return p;
}

} // namespace

TEST(CementSurface, TheLeakIsRedWhereItProjectsAndThereIsNoRedWithoutALeak) {
  forgetDisplay();
  const auto dir = scratchFolder();
  CementSurfaceOptions o; // 800 x 720, title band 12 %
  o.viewDirection[0] = 0;
  o.viewDirection[1] = -1; // camera at -y: screen right is +x, screen up +z (view up)
  o.viewDirection[2] = 0;
  writeCementSurface(cementLabels(true), dir / "leak.png", o);
  const Pixels leak = classify(dir / "leak.png");
  // The documented view (CementSurface.h), worked out by hand: the surfaces lie half a voxel outside the
  // voxel centres, so the union box is x 2.5..24.5, y 4.5..14.5, z 4.5..15.5 mm: centre (13.5, 9.5, 10),
  // diagonal sqrt(22^2 + 10^2 + 11^2); parallel scale 0.55 diagonal over half the 3D area's height.
  const double height3d = 720 * (1 - 0.12), scale = 0.55 * std::sqrt(22.0 * 22 + 10 * 10 + 11 * 11);
  const double pxPerMm = 0.5 * height3d / scale;
  auto px = [&](double xMm) { return 400 + (xMm - 13.5) * pxPerMm; };
  auto py = [&](double zMm) { return 0.5 * height3d + (zMm - 10.0) * pxPerMm; };
  // The leak's face towards the camera: x 19.5..24.5, z 11.5..15.5 mm. Every red pixel lies in it (3 px
  // for the rasteriser and the surface's chamfered edges) and red fills most of it.
  const double slack = 3;
  std::vector<std::array<int, 2>> redSurface;
  std::size_t redLegend = 0; // "red: leaked" in the title band
  for (const auto& p : leak.red) {
    if (p[1] < height3d) redSurface.push_back(p);
    else ++redLegend;
  }
  EXPECT_GT(redLegend, 0u);
  ASSERT_FALSE(redSurface.empty()) << "no red: the leak is not drawn";
  for (const auto& [x, y] : redSurface) {
    ASSERT_GE(x, px(19.5) - slack) << x << ", " << y;
    ASSERT_LE(x, px(24.5) + slack) << x << ", " << y;
    ASSERT_GE(y, py(11.5) - slack) << x << ", " << y;
    ASSERT_LE(y, py(15.5) + slack) << x << ", " << y;
  }
  const double faceArea = (px(24.5) - px(19.5)) * (py(15.5) - py(11.5));
  EXPECT_GT(double(redSurface.size()), 0.6 * faceArea); // the flat face, less its chamfered rim
  EXPECT_LT(double(redSurface.size()), 1.1 * faceArea);
  // The cement in bone is blue, in its own projection (x 2.5..12.5, z 4.5..14.5), besides the legend's text.
  std::size_t blueInBone = 0;
  for (const auto& [x, y] : leak.blue)
    if (x >= px(2.5) - slack && x <= px(12.5) + slack && y >= py(4.5) - slack && y <= py(14.5) + slack) ++blueInBone;
  EXPECT_GT(double(blueInBone), 0.6 * (px(12.5) - px(2.5)) * (py(14.5) - py(4.5)));

  // Without a leak: no red pixel anywhere (surface or legend).
  writeCementSurface(cementLabels(false), dir / "none.png", o);
  const Pixels none = classify(dir / "none.png");
  EXPECT_TRUE(none.red.empty()) << none.red.size() << " red pixels without a leak";
  EXPECT_FALSE(none.blue.empty());
  // No cement at all, or a null map: one clear error, no file.
  auto empty = cementLabels(false);
  for (vtkIdType i = 0; i < empty->GetNumberOfPoints(); ++i) empty->GetPointData()->GetScalars()->SetTuple1(i, 0);
  EXPECT_THROW(writeCementSurface(empty, dir / "empty.png", o), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir / "empty.png"));
  EXPECT_THROW(writeCementSurface(nullptr, dir / "null.png", o), std::invalid_argument);
}

TEST(SurfaceComparison, WithTheLabelMapTheLeakedPartOfTheSimulatedSurfaceIsRed) {
  forgetDisplay();
  const auto dir = scratchFolder();
  // The 0.5 isosurface of all cement (labels 1 and 2) of the CementSurface test's map, as both surfaces.
  auto labels = cementLabels(true);
  auto mask = vtkSmartPointer<vtkImageData>::New();
  mask->CopyStructure(labels);
  mask->AllocateScalars(VTK_FLOAT, 1);
  for (vtkIdType i = 0; i < labels->GetNumberOfPoints(); ++i)
    mask->GetPointData()->GetScalars()->SetTuple1(i, labels->GetPointData()->GetScalars()->GetTuple1(i) > 0 ? 1.0 : 0.0);
  vtkNew<vtkFlyingEdges3D> edges;
  edges->SetInputData(mask);
  edges->SetValue(0, 0.5);
  edges->Update();
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  surface->DeepCopy(edges->GetOutput());
  vtkNew<vtkDoubleArray> zero;
  zero->SetName("DistanceToOtherSurface_mm");
  zero->SetNumberOfTuples(surface->GetNumberOfPoints());
  zero->Fill(0.0);
  surface->GetPointData()->AddArray(zero);
  SurfaceComparisonOptions o; // 1500 x 560, three panels of 500
  o.viewDirection[0] = 0;
  o.viewDirection[1] = -1; // from -y: +x to the right, +z up
  o.viewDirection[2] = 0;
  o.maxDistanceMm = 1.0;
  o.simulationLabels = labels;
  renderSurfaceComparison(surface, surface, dir / "labelled.png", o);
  const Pixels with = classify(dir / "labelled.png");
  // The middle panel (x 500..999) below its title: red only right of the cement's centre (x = 13.5 mm: the
  // leak is at x 19.5..24.5, the block at 2.5..12.5) and above it (z 11.5..15.5 against the centre z = 10),
  // and some red there; the left panel (the experiment) has none.
  std::size_t redMiddle = 0;
  for (const auto& [x, y] : with.red) {
    if (y > 0.85 * 560) continue; // the titles
    EXPECT_FALSE(x < 500) << "red in the experiment's panel at " << x << ", " << y;
    if (x >= 500 && x < 1000) {
      ++redMiddle;
      EXPECT_GT(x, 750) << y;
      EXPECT_GT(y, 280) << x;
    }
  }
  EXPECT_GT(redMiddle, 200u);
  // Without the label map: no red in the middle panel.
  o.simulationLabels = nullptr;
  renderSurfaceComparison(surface, surface, dir / "plain.png", o);
  for (const auto& [x, y] : classify(dir / "plain.png").red) EXPECT_FALSE(x >= 500 && x < 1000) << x << ", " << y;
}
