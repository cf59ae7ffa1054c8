// Oblique, flipped and axis-swapped CTs through the injection (issue 20, item 3). The CT is a porous scaffold
// (ScaffoldCT.h) on a non-cubic grid, and its copies describe the SAME physical voxels with another direction
// matrix: flipped axes, swapped axes, or a 20 degree tilt (resampled). Oracles:
//  * reorientation and paste-back: the value at a physical point, found through ITK's own index<->physical
//    mapping of the copy (not through the code under test), and analytic changes (constant, linear);
//  * flipped/swapped runs: the axial run, an independent run on another array layout (tip pressure within
//    2 %, cement volume within 1 %, cement Dice >= 0.95 through physical points);
//  * tilted run: the input grid and, outside the region of interest, the input's HU (exact), and the
//    injected volume recovered from the pasted HU change (k = 3000 HU per unit relative density) within 5 %.
#include "ProgramRun.h"
#include "ScaffoldCT.h"

#include "cementsph/imaging/AffineRegistration.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/scene/AxisAlignedCT.h"
#include "cementsph/scene/InputGridPaste.h"
#include "vtkSPHInjectionFilter.h"

#include <gtest/gtest.h>
#include <itkIdentityTransform.h>
#include <itkImageRegionConstIteratorWithIndex.h>
#include <nlohmann/json.hpp>
#include <omp.h>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkSmartPointer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace fs = std::filesystem;
using cementsph::imaging::ImageType;

namespace {
const int kOneThread = [] {
  omp_set_num_threads(1); // shared cores, and the runs compared must not differ by thread scheduling
  return 1;
}();

constexpr double kPi = 3.14159265358979323846;
constexpr double kHuPerRelativeDensity = 3000.0; // the filter's default k
constexpr double kCementChangeHu = 0.5 * kHuPerRelativeDensity; // a voxel at least half full of cement
const std::array<long, 3> kSize{40, 44, 48}; // non-cubic: a swapped copy has another array shape
const double kSpacing = 0.5;
const std::array<double, 3> kOrigin{-10.0, 5.0, 20.0};
const std::array<double, 3> kTip{-10.0 + 13.0, 5.0 + 13.0, 20.0 + 13.0}; // pore centre, voxel (26, 26, 26)

// Calls f(index) for every voxel of the image.
template <typename F>
void forEachVoxel(const ImageType* image, F&& f) {
  for (itk::ImageRegionConstIteratorWithIndex<ImageType> it(image, image->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
    f(it.GetIndex());
}

// The axial scaffold: voxel (i, j, k) at kOrigin + 0.5 (i, j, k) mm, identity direction.
ImageType::Pointer axialCt() {
  auto img = ImageType::New();
  ImageType::RegionType region;
  ImageType::SizeType size;
  ImageType::PointType origin;
  for (unsigned a = 0; a < 3; ++a) {
    size[a] = itk::SizeValueType(kSize[a]);
    origin[a] = kOrigin[a];
  }
  region.SetSize(size);
  img->SetRegions(region);
  img->SetSpacing(kSpacing);
  img->SetOrigin(origin);
  img->Allocate();
  forEachVoxel(img, [&](const ImageType::IndexType& i) {
    img->SetPixel(i, cementsph::scene::testing::scaffoldRod(int(i[0]), int(i[1]), int(i[2])) ? 1000.f : -100.f);
  });
  return img;
}

// The same physical voxels stored another way: voxel axis a of the copy runs along patient axis axis[a] with
// sign sign[a]. Built here by hand (index arithmetic), independently of axisAligned().
ImageType::Pointer relabelled(const ImageType* src, std::array<unsigned, 3> axis, std::array<int, 3> sign) {
  const auto srcSize = src->GetLargestPossibleRegion().GetSize();
  auto img = ImageType::New();
  ImageType::RegionType region;
  ImageType::SizeType size;
  ImageType::SpacingType spacing;
  ImageType::DirectionType direction;
  direction.Fill(0.0);
  ImageType::IndexType corner; // the source voxel that becomes voxel 0 of the copy
  for (unsigned a = 0; a < 3; ++a) {
    size[a] = srcSize[axis[a]];
    spacing[a] = src->GetSpacing()[axis[a]];
    direction[axis[a]][a] = sign[a];
    corner[axis[a]] = sign[a] > 0 ? 0 : itk::IndexValueType(srcSize[axis[a]]) - 1;
  }
  ImageType::PointType origin;
  src->TransformIndexToPhysicalPoint(corner, origin);
  region.SetSize(size);
  img->SetRegions(region);
  img->SetSpacing(spacing);
  img->SetDirection(direction);
  img->SetOrigin(origin);
  img->Allocate();
  forEachVoxel(img, [&](const ImageType::IndexType& j) {
    ImageType::IndexType s;
    for (unsigned a = 0; a < 3; ++a) s[axis[a]] = sign[a] > 0 ? j[a] : itk::IndexValueType(srcSize[axis[a]]) - 1 - j[a];
    img->SetPixel(j, src->GetPixel(s));
  });
  return img;
}

// A copy on a grid tilted by `degrees` about the x axis (a gantry tilt), same spacing, centred on the same
// point, the scaffold sampled trilinearly (air outside it): the same physical object in an oblique series.
ImageType::Pointer tiltedCt(const ImageType* src, double degrees) {
  const double t = degrees * kPi / 180.0;
  ImageType::DirectionType r;
  r.Fill(0.0);
  r[0][0] = 1;
  r[1][1] = std::cos(t);
  r[1][2] = -std::sin(t);
  r[2][1] = std::sin(t);
  r[2][2] = std::cos(t);
  auto grid = ImageType::New();
  ImageType::RegionType region;
  ImageType::SizeType size;
  for (unsigned a = 0; a < 3; ++a) size[a] = itk::SizeValueType(kSize[a]);
  region.SetSize(size);
  grid->SetRegions(region);
  grid->SetSpacing(kSpacing);
  grid->SetDirection(r);
  ImageType::PointType origin; // centre - R (h (n - 1) / 2)
  for (unsigned a = 0; a < 3; ++a) {
    double c = kOrigin[a] + kSpacing * double(kSize[a] - 1) / 2.0;
    for (unsigned b = 0; b < 3; ++b) c -= r[a][b] * kSpacing * double(kSize[b] - 1) / 2.0;
    origin[a] = c;
  }
  grid->SetOrigin(origin);
  auto identity = itk::IdentityTransform<double, 3>::New();
  return cementsph::imaging::resampleOnto(src, grid, identity, -1000.f);
}

struct FilterRun {
  nlohmann::json metrics;
  ImageType::Pointer input, simulated; // the filter's input and its simulated-CT output, as ITK images
  vtkSmartPointer<vtkImageData> vtkInput, vtkSimulated;
};

FilterRun runFilter(const ImageType* ct, double roiSizeMm) {
  FilterRun run;
  run.vtkInput = cementsph::imaging::toVtk(ct);
  auto filter = vtkSmartPointer<vtkSPHInjectionFilter>::New();
  filter->SetInputDataObject(0, run.vtkInput);
  filter->SetTipMm(kTip[0], kTip[1], kTip[2]);
  filter->SetVolumeMl(0.1);
  filter->SetCannulaLengthMm(5);
  filter->SetROISizeMm(roiSizeMm);
  filter->Update();
  EXPECT_EQ(filter->GetErrorMessage(), "");
  if (!filter->GetErrorMessage().empty()) return run;
  run.metrics = nlohmann::json::parse(filter->GetMetricsJSON());
  run.vtkSimulated = vtkSmartPointer<vtkImageData>::New();
  run.vtkSimulated->DeepCopy(filter->GetSimulatedCTOutput());
  run.input = cementsph::imaging::imageFromVtk(run.vtkInput);
  run.simulated = cementsph::imaging::imageFromVtk(run.vtkSimulated);
  return run;
}

// Dice of the cement masks (HU change >= kCementChangeHu) of two runs on the same physical voxels, voxel
// matched to voxel through its physical centre.
double cementDice(const FilterRun& a, const FilterRun& b) {
  std::size_t inA = 0, inB = 0, both = 0, unmatched = 0;
  forEachVoxel(a.input, [&](const ImageType::IndexType& i) {
    ImageType::PointType p;
    a.input->TransformIndexToPhysicalPoint(i, p);
    ImageType::IndexType j;
    if (!b.input->TransformPhysicalPointToIndex(p, j)) {
      ++unmatched;
      return;
    }
    const bool ca = a.simulated->GetPixel(i) - a.input->GetPixel(i) >= kCementChangeHu;
    const bool cb = b.simulated->GetPixel(j) - b.input->GetPixel(j) >= kCementChangeHu;
    inA += ca;
    inB += cb;
    both += ca && cb;
  });
  EXPECT_EQ(unmatched, 0u);
  EXPECT_GT(inA, 100u); // 0.1 ml is ~800 voxels of 0.125 mm^3: a mask worth comparing
  return inA + inB == 0 ? 0.0 : 2.0 * double(both) / double(inA + inB);
}

void expectSameGrid(const ImageType* a, const ImageType* b) {
  EXPECT_EQ(a->GetLargestPossibleRegion(), b->GetLargestPossibleRegion());
  for (unsigned r = 0; r < 3; ++r) {
    EXPECT_EQ(a->GetOrigin()[r], b->GetOrigin()[r]) << r;
    EXPECT_EQ(a->GetSpacing()[r], b->GetSpacing()[r]) << r;
    for (unsigned c = 0; c < 3; ++c) EXPECT_EQ(a->GetDirection()[r][c], b->GetDirection()[r][c]) << r << c;
  }
}

// A small anisotropic CT whose every voxel has its own value (i + 100 j + 10000 k).
ImageType::Pointer labelledCt() {
  auto img = ImageType::New();
  ImageType::RegionType region;
  ImageType::SizeType size{{7, 9, 11}};
  region.SetSize(size);
  img->SetRegions(region);
  ImageType::SpacingType spacing;
  spacing[0] = 0.5;
  spacing[1] = 0.75;
  spacing[2] = 1.25;
  img->SetSpacing(spacing);
  ImageType::PointType origin;
  origin[0] = 3.0;
  origin[1] = -7.5;
  origin[2] = 100.0;
  img->SetOrigin(origin);
  img->Allocate();
  forEachVoxel(img, [&](const ImageType::IndexType& i) { img->SetPixel(i, float(i[0] + 100 * i[1] + 10000 * i[2])); });
  return img;
}

// `cementsph inject` as a user runs it, pictures on: `ct` written as NRRD and the scene (its tip the test's,
// then `sceneKeys`) in a fresh scratch folder `name`; the results in name/out.
cementsph::testing::ProgramRun injectCommand(const std::string& name, const ImageType* ct, const std::string& sceneKeys,
                                             fs::path& dir) {
  const std::string program = std::string(CEMENTSPH_BINARY_DIR) + "/bin/cementsph";
  dir = fs::path(CEMENTSPH_BINARY_DIR) / "Testing" / "scratch" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  if (!fs::exists(program)) return {127, "", program + ": build the cementsph target first"};
  cementsph::imaging::writeVolume(ct, (dir / "ct.nrrd").string());
  std::ofstream(dir / "scene.json") << "{\"tip_mm\": [" << kTip[0] << ", " << kTip[1] << ", " << kTip[2] << "], "
                                    << sceneKeys << "}";
  setenv("OMP_NUM_THREADS", "1", 1); // the child inherits it: one thread on shared cores
  return cementsph::testing::runProgram(program, {"inject", "--ct", (dir / "ct.nrrd").string(), "--scene",
                                                  (dir / "scene.json").string(), "--out", (dir / "out").string(), "--quiet"});
}
} // namespace

// (c) A flipped or axis-swapped series is reoriented exactly: identity direction, every voxel's value at its
// own physical centre, no interpolation; and it is the axial array itself.
TEST(ObliqueCT, SignedPermutationIsReorientedExactly) {
  const auto axial = labelledCt();
  const std::array<std::array<unsigned, 3>, 3> axes{{{0, 1, 2}, {2, 0, 1}, {1, 2, 0}}};
  const std::array<std::array<int, 3>, 3> signs{{{-1, 1, -1}, {1, -1, 1}, {-1, -1, -1}}};
  for (std::size_t c = 0; c < axes.size(); ++c) {
    const auto copy = relabelled(axial, axes[c], signs[c]);
    ASSERT_FALSE(cementsph::scene::isAxisAligned(copy));
    ASSERT_TRUE(cementsph::scene::axisPermutation(copy).has_value());
    const auto aligned = cementsph::scene::axisAligned(copy);
    EXPECT_TRUE(cementsph::scene::isAxisAligned(aligned));
    // The axial CT's grid, as built above (spacing 0.5/0.75/1.25 mm: not resampled onto 0.5 mm).
    expectSameGrid(aligned, axial);
    std::size_t same = 0;
    forEachVoxel(aligned, [&](const ImageType::IndexType& i) {
      ImageType::PointType p;
      aligned->TransformIndexToPhysicalPoint(i, p);
      itk::ContinuousIndex<double, 3> u;
      if (!copy->TransformPhysicalPointToContinuousIndex(p, u)) return;
      ImageType::IndexType j;
      bool centre = true; // the copy's voxel centre is this point: nothing to interpolate
      for (unsigned a = 0; a < 3; ++a) {
        j[a] = std::lround(u[a]);
        centre = centre && std::abs(u[a] - double(j[a])) <= 1e-9;
      }
      same += centre && aligned->GetPixel(i) == copy->GetPixel(j) && aligned->GetPixel(i) == axial->GetPixel(i);
    });
    EXPECT_EQ(same, 7u * 9u * 11u) << "case " << c;
  }
  // A region that does not start at index 0 (ITK allows it; the physical voxels unchanged): the same.
  const auto copy = relabelled(axial, axes[1], signs[1]);
  auto shifted = ImageType::New();
  shifted->CopyInformation(copy);
  ImageType::RegionType region = copy->GetLargestPossibleRegion();
  region.SetIndex({{3, -2, 5}});
  shifted->SetRegions(region);
  ImageType::PointType shiftedOrigin = copy->GetOrigin(); // voxel (3, -2, 5) where voxel (0, 0, 0) was
  for (unsigned r = 0; r < 3; ++r)
    for (unsigned a = 0; a < 3; ++a)
      shiftedOrigin[r] -= copy->GetDirection()[r][a] * copy->GetSpacing()[a] * double(region.GetIndex()[a]);
  shifted->SetOrigin(shiftedOrigin);
  shifted->Allocate();
  std::copy_n(copy->GetBufferPointer(), region.GetNumberOfPixels(), shifted->GetBufferPointer());
  const auto fromShifted = cementsph::scene::axisAligned(shifted);
  expectSameGrid(fromShifted, axial);
  EXPECT_TRUE(std::equal(axial->GetBufferPointer(), axial->GetBufferPointer() + region.GetNumberOfPixels(),
                         fromShifted->GetBufferPointer()));
  // A truly oblique series is still resampled: each patient axis at the spacing of the CT axis most nearly along
  // it (rotated 0.3 rad about z: x from voxel axis 0, cos 0.3 = 0.955 against sin 0.3 = 0.296; y from axis 1).
  auto oblique = ImageType::New();
  oblique->Graft(axial);
  ImageType::DirectionType r;
  r.SetIdentity();
  r[0][0] = r[1][1] = std::cos(0.3);
  r[0][1] = -std::sin(0.3);
  r[1][0] = std::sin(0.3);
  oblique->SetDirection(r);
  EXPECT_FALSE(cementsph::scene::axisPermutation(oblique).has_value());
  const auto resampled = cementsph::scene::axisAligned(oblique);
  EXPECT_DOUBLE_EQ(resampled->GetSpacing()[0], 0.5);
  EXPECT_DOUBLE_EQ(resampled->GetSpacing()[1], 0.75);
  EXPECT_DOUBLE_EQ(resampled->GetSpacing()[2], 1.25);
}

// (d) Paste-back on hand-made simulated images with known changes.
TEST(ObliqueCT, PasteBackPutsKnownChangesOnKnownInputVoxels) {
  using cementsph::scene::alignedBackgroundOn;
  using cementsph::scene::pasteOntoInputGrid;
  const auto axial = labelledCt();
  // Swapped and flipped input (copy axis 0 along +y, 1 along +z, 2 along -x). The simulated image: a 3x3x3 block of the axial grid whose voxel (1, 1, 1) is axial voxel
  // (4, 5, 6), +500 HU there only.
  const auto input = relabelled(axial, {1, 2, 0}, {1, 1, -1});
  auto sim = ImageType::New();
  ImageType::RegionType block;
  block.SetSize({{3, 3, 3}});
  sim->SetRegions(block);
  sim->SetSpacing(axial->GetSpacing());
  ImageType::PointType centre; // axial voxel (4, 5, 6), by hand: origin + spacing * index
  centre[0] = 3.0 + 0.5 * 4;
  centre[1] = -7.5 + 0.75 * 5;
  centre[2] = 100.0 + 1.25 * 6;
  ImageType::PointType simOrigin;
  for (unsigned a = 0; a < 3; ++a) simOrigin[a] = centre[a] - sim->GetSpacing()[a];
  sim->SetOrigin(simOrigin);
  sim->Allocate();
  auto background = alignedBackgroundOn(input, sim);
  EXPECT_EQ(background->GetPixel({{1, 1, 1}}), 4.f + 100.f * 5 + 10000.f * 6); // the axial value there
  for (std::size_t v = 0; v < 27; ++v) sim->GetBufferPointer()[v] = background->GetBufferPointer()[v];
  sim->SetPixel({{1, 1, 1}}, sim->GetPixel({{1, 1, 1}}) + 500.f);
  auto out = pasteOntoInputGrid(input, sim, background);
  expectSameGrid(out, input);
  // The input voxel at that point, by hand: copy axis 0 runs along y (index 5), axis 1 along z (6), axis 2
  // along -x (7 voxels: 6 - 4 = 2).
  const ImageType::IndexType known{{5, 6, 2}};
  ImageType::PointType p;
  input->TransformIndexToPhysicalPoint(known, p);
  for (unsigned a = 0; a < 3; ++a) ASSERT_NEAR(p[a], centre[a], 1e-9);
  EXPECT_EQ(out->GetPixel(known), 4.f + 100.f * 5 + 10000.f * 6 + 500.f);
  std::size_t changed = 0;
  for (std::size_t v = 0; v < input->GetLargestPossibleRegion().GetNumberOfPixels(); ++v)
    changed += out->GetBufferPointer()[v] != input->GetBufferPointer()[v];
  EXPECT_EQ(changed, 1u);

  // Oblique input (30 degrees about z), simulated change linear in position on an axis-aligned block: linear
  // interpolation reproduces a linear field, so every input voxel whose centre lies between the block's
  // voxel centres gets input + change(p) (to float round-off), those outside the block's box nothing.
  auto oblique = ImageType::New();
  oblique->Graft(axial);
  ImageType::DirectionType r;
  r.SetIdentity();
  r[0][0] = r[1][1] = std::cos(kPi / 6);
  r[0][1] = -std::sin(kPi / 6);
  r[1][0] = std::sin(kPi / 6);
  oblique->SetDirection(r);
  auto box = ImageType::New();
  ImageType::RegionType boxRegion;
  boxRegion.SetSize({{8, 8, 8}});
  box->SetRegions(boxRegion);
  box->SetSpacing(0.5);
  ImageType::PointType boxOrigin;
  boxOrigin[0] = 2.2;
  boxOrigin[1] = -5.1;
  boxOrigin[2] = 104.3;
  box->SetOrigin(boxOrigin);
  box->Allocate();
  auto obliqueBackground = alignedBackgroundOn(oblique, box);
  auto change = [&](const ImageType::PointType& q) {
    return 40.0 * (q[0] - 2.2) - 25.0 * (q[1] + 5.1) + 10.0 * (q[2] - 104.3) + 300.0;
  };
  forEachVoxel(box, [&](const ImageType::IndexType& b) {
    ImageType::PointType q;
    box->TransformIndexToPhysicalPoint(b, q);
    box->SetPixel(b, float(obliqueBackground->GetPixel(b) + change(q)));
  });
  auto obliqueOut = pasteOntoInputGrid(oblique, box, obliqueBackground);
  expectSameGrid(obliqueOut, oblique);
  std::size_t inside = 0, outside = 0;
  forEachVoxel(oblique, [&](const ImageType::IndexType& i) {
    ImageType::PointType q;
    oblique->TransformIndexToPhysicalPoint(i, q);
    bool interior = true, inBox = true;
    for (unsigned a = 0; a < 3; ++a) {
      const double u = (q[a] - boxOrigin[a]) / 0.5;
      interior = interior && u >= 0 && u <= 7;
      inBox = inBox && u >= -0.5 && u <= 7.5;
    }
    if (interior) {
      ++inside;
      // float values up to ~1e5 HU: 2e-2 HU is a few ulp
      EXPECT_NEAR(obliqueOut->GetPixel(i), oblique->GetPixel(i) + change(q), 2e-2) << i;
    } else if (!inBox) {
      ++outside;
      EXPECT_EQ(obliqueOut->GetPixel(i), oblique->GetPixel(i)) << i;
    }
  });
  EXPECT_GT(inside, 10u);
  EXPECT_GT(outside, 100u);

  // A simulated block reaching past the input's edge, and one wholly outside: no write leaves the buffer,
  // and only voxels inside the input change.
  auto edge = ImageType::New();
  edge->Graft(box);
  ImageType::PointType far;
  far[0] = 0.0; // the input's centres start at x 3.0, y -7.5, z 100 mm: the block's box straddles that corner
  far[1] = -9.0;
  far[2] = 97.0;
  edge->SetOrigin(far);
  auto edgeBackground = alignedBackgroundOn(input, edge);
  auto edgeSim = ImageType::New();
  edgeSim->SetRegions(boxRegion);
  edgeSim->CopyInformation(edge);
  edgeSim->Allocate();
  for (std::size_t v = 0; v < 512; ++v) edgeSim->GetBufferPointer()[v] = edgeBackground->GetBufferPointer()[v] + 7.f;
  auto edgeOut = pasteOntoInputGrid(input, edgeSim, edgeBackground);
  std::size_t edgeChanged = 0;
  for (std::size_t v = 0; v < input->GetLargestPossibleRegion().GetNumberOfPixels(); ++v)
    edgeChanged += edgeOut->GetBufferPointer()[v] != input->GetBufferPointer()[v];
  EXPECT_GT(edgeChanged, 0u);
  ImageType::PointType away;
  away[0] = 500;
  away[1] = 500;
  away[2] = 500;
  edge->SetOrigin(away);
  edgeSim->SetOrigin(away);
  auto awayOut = pasteOntoInputGrid(input, edgeSim, alignedBackgroundOn(input, edge));
  for (std::size_t v = 0; v < input->GetLargestPossibleRegion().GetNumberOfPixels(); ++v)
    ASSERT_EQ(awayOut->GetBufferPointer()[v], input->GetBufferPointer()[v]);
  // A background on another grid is refused in one line.
  EXPECT_THROW(pasteOntoInputGrid(input, sim, obliqueBackground), std::invalid_argument);
}

// (b) Flipped and swapped copies give the axial run's figures.
TEST(ObliqueCT, FlippedAndSwappedSeriesGiveTheAxialFigures) {
  const auto axial = axialCt();
  const FilterRun a = runFilter(axial, 40.0);
  ASSERT_FALSE(a.metrics.is_null());
  const double pa = a.metrics["final_tip_pressure_pa"].get<double>(), va = a.metrics["cement_volume_ml"].get<double>();
  std::cout << "axial: tip " << pa << " Pa, cement " << va << " ml\n";
  const std::array<std::array<unsigned, 3>, 2> axes{{{0, 1, 2}, {2, 0, 1}}};
  const std::array<std::array<int, 3>, 2> signs{{{-1, 1, -1}, {1, -1, 1}}};
  const char* names[] = {"flipped x,z", "swapped (z,-x,y)"};
  for (std::size_t c = 0; c < 2; ++c) {
    const auto copy = relabelled(axial, axes[c], signs[c]);
    const FilterRun b = runFilter(copy, 40.0);
    ASSERT_FALSE(b.metrics.is_null()) << names[c];
    EXPECT_EQ(b.metrics["ct_orientation"], "reoriented") << names[c]; // exact: nothing interpolated
    EXPECT_FALSE(b.metrics["ct_resampled_to_axis_aligned"].get<bool>()) << names[c];
    expectSameGrid(b.simulated, copy); // the output on the copy's own grid
    const double pb = b.metrics["final_tip_pressure_pa"].get<double>(), vb = b.metrics["cement_volume_ml"].get<double>();
    const double dice = cementDice(a, b);
    std::cout << names[c] << ": tip " << pb << " Pa, cement " << vb << " ml, Dice " << dice << "\n";
    EXPECT_NEAR(pb, pa, 0.02 * std::abs(pa)) << names[c];
    EXPECT_NEAR(vb, va, 0.01 * va) << names[c];
    EXPECT_GE(dice, 0.95) << names[c];
    RecordProperty(std::string("tip_pressure_pa_") + std::to_string(c), std::to_string(pb));
    RecordProperty(std::string("dice_") + std::to_string(c), std::to_string(dice));
  }
}

// (a) A 20 degree tilted series runs without a crash, and the simulated CT lies on the input's grid.
TEST(ObliqueCT, TiltedSeriesPastesBackOntoItsOwnGrid) {
  const double roi = 12.0;
  const auto tilted = tiltedCt(axialCt(), 20.0);
  const FilterRun t = runFilter(tilted, roi);
  ASSERT_FALSE(t.metrics.is_null());
  EXPECT_TRUE(t.metrics["ct_resampled_to_axis_aligned"].get<bool>());
  EXPECT_EQ(t.metrics["ct_orientation"], "resampled");
  int inDims[3], outDims[3];
  t.vtkInput->GetDimensions(inDims);
  t.vtkSimulated->GetDimensions(outDims);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(outDims[a], inDims[a]);
    EXPECT_EQ(t.vtkSimulated->GetOrigin()[a], t.vtkInput->GetOrigin()[a]);
    EXPECT_EQ(t.vtkSimulated->GetSpacing()[a], t.vtkInput->GetSpacing()[a]);
    for (int b = 0; b < 3; ++b)
      EXPECT_EQ(t.vtkSimulated->GetDirectionMatrix()->GetElement(a, b), t.vtkInput->GetDirectionMatrix()->GetElement(a, b));
  }
  // Outside the region of interest (voxel centres within roi/2 of the tip on the 0.5 mm aligned grid, whose
  // voxel boxes reach 0.25 mm further; 0.5 mm margin) the input's HU exactly.
  const auto region = t.input->GetLargestPossibleRegion();
  std::size_t outside = 0, differing = 0;
  double changeSum = 0;
  forEachVoxel(t.input, [&](const ImageType::IndexType& i) {
    ImageType::PointType p;
    t.input->TransformIndexToPhysicalPoint(i, p);
    double far = 0;
    for (unsigned a = 0; a < 3; ++a) far = std::max(far, std::abs(p[a] - kTip[a]));
    changeSum += double(t.simulated->GetPixel(i)) - double(t.input->GetPixel(i));
    if (far > roi / 2 + 0.5) {
      ++outside;
      differing += t.simulated->GetPixel(i) != t.input->GetPixel(i);
    }
  });
  EXPECT_GT(outside, region.GetNumberOfPixels() / 2);
  EXPECT_EQ(differing, 0u);
  // Cement at the tip, and the injected volume back from the pasted change: sum(change) / k * voxel volume.
  ImageType::PointType tipPoint;
  for (unsigned a = 0; a < 3; ++a) tipPoint[a] = kTip[a];
  ImageType::IndexType tipVoxel; // the input voxel nearest the tip
  ASSERT_TRUE(t.input->TransformPhysicalPointToIndex(tipPoint, tipVoxel));
  EXPECT_GT(t.simulated->GetPixel(tipVoxel) - t.input->GetPixel(tipVoxel), kCementChangeHu);
  const double pastedMl = changeSum / kHuPerRelativeDensity * std::pow(kSpacing, 3) * 1e-3;
  const double injected = t.metrics["volume_injected_ml"].get<double>();
  std::cout << "tilted 20 deg: tip " << t.metrics["final_tip_pressure_pa"].get<double>() << " Pa, cement "
            << t.metrics["cement_volume_ml"].get<double>() << " ml, pasted " << pastedMl << " ml of " << injected << "\n";
  EXPECT_NEAR(pastedMl, injected, 0.05 * injected);
}

// `cementsph inject` on a tilted NRRD, pictures on: exit 0, no crash; its simulated_ct.nrrd lies on the input's
// own grid (size, origin, spacing and the tilted direction), so it subtracts from the input voxel by voxel.
TEST(ObliqueCT, InjectCommandOnATiltedNrrd) {
  fs::path dir;
  const auto input = tiltedCt(axialCt(), 20.0);
  const auto r = injectCommand("oblique-inject", input, R"("volume_ml": 0.1, "cannula_length_mm": 5, "roi_size_mm": 12)",
                               dir);
  ASSERT_EQ(r.exitCode, 0) << r.out << r.err;
  EXPECT_TRUE(fs::exists(dir / "out" / "tip_pressure.png")) << "pictures on";
  const auto sim = cementsph::imaging::readVolume((dir / "out" / "simulated_ct.nrrd").string());
  EXPECT_EQ(sim->GetLargestPossibleRegion().GetSize(), input->GetLargestPossibleRegion().GetSize());
  for (unsigned a = 0; a < 3; ++a) {
    EXPECT_NEAR(sim->GetSpacing()[a], input->GetSpacing()[a], 1e-9);
    EXPECT_NEAR(sim->GetOrigin()[a], input->GetOrigin()[a], 1e-6);
    for (unsigned b = 0; b < 3; ++b) EXPECT_NEAR(sim->GetDirection()[a][b], input->GetDirection()[a][b], 1e-9);
  }
  EXPECT_FALSE(cementsph::scene::isAxisAligned(sim));
  // The cement's change, summed over the input grid, is the injected volume (k = 3000 HU per relative density).
  double change = 0;
  forEachVoxel(input, [&](const ImageType::IndexType& i) { change += sim->GetPixel(i) - input->GetPixel(i); });
  const double pastedMl = change / kHuPerRelativeDensity * std::pow(kSpacing, 3) * 1e-3;
  EXPECT_NEAR(pastedMl, 0.1, 0.005) << "ml of cement on the input grid";
}

// The same with bone as a continuum (a box of 150-250 HU bone in 1 mm of cortex, fat outside), so that inject
// also draws cement_slices.png and cement_surface.png from the files of an oblique run: exit 0, all pictures.
TEST(ObliqueCT, InjectCommandDrawsEveryPictureForATiltedContinuumCt) {
  const auto tilted = tiltedCt(axialCt(), 20.0); // the grid only: every value is set below from its position
  forEachVoxel(tilted, [&](const ImageType::IndexType& i) {
    ImageType::PointType p;
    tilted->TransformIndexToPhysicalPoint(i, p);
    bool inBox = true, inMarrow = true; // box: 1.5 mm inside the axial CT's faces; cortex 1 mm thick
    for (unsigned a = 0; a < 3; ++a) {
      const double lo = kOrigin[a] + 1.5, hi = kOrigin[a] + kSpacing * double(kSize[a] - 1) - 1.5;
      inBox = inBox && p[a] >= lo && p[a] <= hi;
      inMarrow = inMarrow && p[a] >= lo + 1.0 && p[a] <= hi - 1.0;
    }
    tilted->SetPixel(i, !inBox ? -100.f : !inMarrow ? 1000.f : p[0] < kTip[0] ? 150.f : 250.f);
  });
  fs::path dir;
  const auto r = injectCommand("oblique-inject-continuum", tilted, R"("volume_ml": 0.3, "snapshot_interval_s": 1000, "direction": [0, 0, 1])", dir);
  ASSERT_EQ(r.exitCode, 0) << r.out << r.err;
  for (const char* f : {"tip_pressure.png", "injection_pressure.png", "cement_slices.png", "cement_surface.png"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  std::ifstream in(dir / "out" / "metrics.json");
  const nlohmann::json m = nlohmann::json::parse(in);
  EXPECT_EQ(m["bone_model"].get<std::string>(), "continuum");
  EXPECT_NEAR(m["cement_volume_ml"].get<double>(), 0.3, 0.003); // volume kept (1 %)
}
