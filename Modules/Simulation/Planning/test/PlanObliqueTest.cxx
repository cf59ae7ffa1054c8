// plan on an oblique series (issue 20 item 5: "oblique scans plan as fast as axial ones"): the vertebra
// phantom and a copy of it on a grid tilted 20 degrees about x (a gantry tilt; the same physical object,
// sampled trilinearly), planned with the same request. The plan aligns the oblique CT once, not once per
// injection; its aligned grid takes, along each patient axis, the spacing of the CT axis nearest it (1 x 1 x 1.5
// mm here) over the tilted box, whose corners are air (kOutsideScanHu). Each injection's work scales with the
// voxels it is given: its region of interest (the same size on both grids) and the bone rule's 100 mm cube
// about the tip, which the rule cuts to the box of the voxels that are not air (VertebraAnatomy.cpp), so the
// tilted grid's air corners cost nothing.
// Oracles: the same trajectory verdict; the best plans' coverage within 0.1 of each other (the tilted CT is a
// trilinear resampling of the axial one, so the two runs differ by the interpolation only). Speed is not
// asserted here (a test is no benchmark): the CPU time of each plan is printed, and
// Testing/Benchmarks/run-all.sh (section plan) reads the printed line into BENCHMARKS.md's tilted / axial ratio.
#include "cementsph/imaging/AffineRegistration.h"
#include "cementsph/phantom/VertebraPhantom.h"
#include "cementsph/planning/InjectionPlanner.h"
#include "cementsph/scene/InjectionRunner.h"
#include "VertebraPlanRequest.h"
#include "VertebraVariant.h"

#include <gtest/gtest.h>
#include <itkIdentityTransform.h>
#include <itkImageRegionIteratorWithIndex.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include <algorithm>
#include <ctime>
#include <omp.h>
#include <cmath>
#include <iostream>
#include <set>

namespace {
using namespace cementsph;

imaging::ImageType::Pointer tilted(const imaging::ImageType* src, double degrees) {
  const double t = degrees * 3.14159265358979323846 / 180.0;
  imaging::ImageType::DirectionType r;
  r.SetIdentity();
  r[1][1] = std::cos(t);
  r[1][2] = -std::sin(t);
  r[2][1] = std::sin(t);
  r[2][2] = std::cos(t);
  auto grid = imaging::ImageType::New();
  grid->SetRegions(src->GetLargestPossibleRegion());
  grid->SetSpacing(src->GetSpacing());
  grid->SetDirection(r);
  // Centred on the source's centre: origin = centre - R (spacing (n - 1) / 2).
  const auto size = src->GetLargestPossibleRegion().GetSize();
  imaging::ImageType::PointType origin;
  for (unsigned a = 0; a < 3; ++a) {
    double c = src->GetOrigin()[a] + src->GetSpacing()[a] * double(size[a] - 1) / 2.0;
    for (unsigned b = 0; b < 3; ++b) c -= r[a][b] * src->GetSpacing()[b] * double(size[b] - 1) / 2.0;
    origin[a] = c;
  }
  grid->SetOrigin(origin);
  return imaging::resampleOnto(src, grid, itk::IdentityTransform<double, 3>::New(), -1000.f);
}

// The body's centre is at (field_x / 2, 21, field_z / 2) (VertebraPhantom.h): the default field's plan, moved with it.
planning::PlanRequest request(const phantom::VertebraOptions& o) {
  const Eigen::Vector3d shift(o.fieldMm[0] / 2 - 32, 0, o.fieldMm[2] / 2 - 22.5);
  // transpedicular, clear of the canal (PlanTrajectoryTest)
  planning::PlanRequest r = planning::testing::transpedicularRequest(Eigen::Vector3d(32, 21, 22.5) + shift,
                                                                     Eigen::Vector3d(48.5, 52.4, 22.5) + shift);
  r.minDepthMm = 15;
  r.targetRadiusMm = 6;
  r.minVolumeMl = 1;
  r.maxVolumeMl = 3;
  r.maxLeakageMl = 0.05;
  r.maxEvaluations = 12;
  r.starts = 2;
  return r;
}

// CPU seconds of this process (one OpenMP thread: see the test), steadier than wall time on a shared machine.
double seconds(const std::function<void()>& f) {
  const std::clock_t t0 = std::clock();
  f();
  return double(std::clock() - t0) / CLOCKS_PER_SEC;
}

void planBothWays(const phantom::VertebraOptions& o, int repeats) {
  omp_set_num_threads(1); // the work itself, not how the cores were shared
  const phantom::VertebraResult v = phantom::makeVertebra(o);
  const auto oblique = tilted(v.ct, 20.0);
  const planning::PlanRequest r = request(o);
  planning::PlanResult axialPlan, obliquePlan;
  // Interleaved, the faster of each kept.
  double axialS = 1e300, obliqueS = 1e300;
  for (int repeat = 0; repeat < repeats; ++repeat) {
    axialS = std::min(axialS, seconds([&] { axialPlan = planning::planInjection(v.ct, r); }));
    obliqueS = std::min(obliqueS, seconds([&] { obliquePlan = planning::planInjection(oblique, r); }));
  }
  // The two searches may take different numbers of injections (the tilted CT's interpolation moves the
  // optimiser's path): the ratio per injection says what the tilt costs each one.
  const double axialN = double(axialPlan.evaluations.size()), obliqueN = double(obliquePlan.evaluations.size());
  std::cout << "plan on a " << o.fieldMm[0] << " x " << o.fieldMm[1] << " x " << o.fieldMm[2] << " mm field, "
            << axialN << " / " << obliqueN << " injections, CPU: axial " << axialS << " s, tilted 20 deg " << obliqueS
            << " s (" << obliqueS / axialS << "x; per injection " << (obliqueS / obliqueN) / (axialS / axialN)
            << "x); best coverage " << axialPlan.best.coverage << " / "
            << obliquePlan.best.coverage << ", volume " << axialPlan.best.volumeMl << " / " << obliquePlan.best.volumeMl
            << " ml\n";
  EXPECT_EQ(axialPlan.trajectory.verdict, "clear") << axialPlan.trajectory.message;
  EXPECT_EQ(obliquePlan.trajectory.verdict, axialPlan.trajectory.verdict) << obliquePlan.trajectory.message;
  EXPECT_TRUE(axialPlan.best.failure.empty());
  EXPECT_TRUE(obliquePlan.best.failure.empty()) << obliquePlan.best.failure;
  EXPECT_NEAR(obliquePlan.best.coverage, axialPlan.best.coverage, 0.1);
}

// The bundled phantom's field (64 x 70 x 45 mm): the tilted copy's aligned grid (the series' own spacings over the
// tilted box, 64 x 81 x 66 mm) has about 1.7x the axial grid's voxels, the extra all air: the bone rule's cube,
// which holds the whole field, is cut back to about the axial field.
TEST(PlanOblique, ATiltedCopyPlansAlike) { planBothWays({}, 2); }

// A clinical-size field (200 x 70 x 200 mm, 1.9 million voxels; tilted about x, so the vertebra, near the y
// centre, stays inside the tilted grid): aligning the whole scan for every injection
// would dominate; aligned once, the injections cost what they cost on the axial scan.
TEST(PlanOblique, ATiltedClinicalSizeScanPlansAlike) {
  phantom::VertebraOptions o;
  o.fieldMm = {200, 70, 200};
  planBothWays(o, 1);
}

// The same voxels stored with other index axes, the direction saying so: "swapped" (index axes z, -x, y) or
// "flipped" (-x, -y, z). New axis a is the source's axis from[a], run forwards (sign +1) or backwards (-1).
imaging::ImageType::Pointer relaid(const imaging::ImageType* src, const std::array<unsigned, 3>& from,
                                   const std::array<int, 3>& sign) {
  const auto n = src->GetLargestPossibleRegion().GetSize();
  imaging::ImageType::SizeType size;
  imaging::ImageType::SpacingType spacing;
  imaging::ImageType::DirectionType direction;
  direction.Fill(0.0);
  imaging::ImageType::IndexType first;
  for (unsigned a = 0; a < 3; ++a) {
    size[a] = n[from[a]];
    spacing[a] = src->GetSpacing()[from[a]];
    direction[from[a]][a] = sign[a]; // the source's direction is the identity
    first[from[a]] = sign[a] > 0 ? 0 : itk::IndexValueType(n[from[a]]) - 1;
  }
  imaging::ImageType::PointType origin;
  src->TransformIndexToPhysicalPoint(first, origin);
  auto out = imaging::ImageType::New();
  out->SetRegions(imaging::ImageType::RegionType(size));
  out->SetSpacing(spacing);
  out->SetDirection(direction);
  out->SetOrigin(origin);
  out->Allocate();
  for (itk::ImageRegionIteratorWithIndex<imaging::ImageType> it(out, out->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it) {
    imaging::ImageType::IndexType o;
    for (unsigned a = 0; a < 3; ++a)
      o[from[a]] = sign[a] > 0 ? it.GetIndex()[a] : itk::IndexValueType(n[from[a]]) - 1 - it.GetIndex()[a];
    it.Set(src->GetPixel(o));
  }
  return out;
}

} // namespace

// A flipped and axis-swapped copy of the anatomy variant (marrow fat, discs, a vein; issue 20 "Done when": oblique
// and flipped copies give the same figures) injects and plans as the axial CT does: a pure permutation or flip is
// reoriented without resampling (AxisAlignedCT.h), so each injection sees the same voxels at the same physical
// places. The copy stores the voxels with index axes (z, -x, -y). The oracle is the axial CT's run, an independent
// run on another array layout; the copy's voxels are checked to lie at the source's physical points through ITK's
// own index-to-point mapping first. Tolerances: the 2 % on pressure and Dice >= 0.95; leakage within one
// voxel (1.5 mm^3); coverage within 0.01; the best plan's depth and volume within the optimiser's resolution
// (0.25 mm, 0.05 ml).
TEST(PlanOblique, AFlippedSwappedCopyOfTheVariantInjectsAndPlansAsTheAxial) {
  const phantom::VertebraOptions o = cementsph::testing::vertebraAnatomyVariant();
  const phantom::VertebraResult v = phantom::makeVertebra(o);
  const auto copy = relaid(v.ct, {2, 0, 1}, {1, -1, -1});
  {
    // Index (1, 2, 3) of the copy is the source's voxel at the same physical point, with the same value.
    imaging::ImageType::IndexType q{{1, 2, 3}}, src;
    imaging::ImageType::PointType p;
    copy->TransformIndexToPhysicalPoint(q, p);
    ASSERT_TRUE(v.ct->TransformPhysicalPointToIndex(p, src));
    ASSERT_EQ(copy->GetPixel(q), v.ct->GetPixel(src));
  }
  // An injection that leaks into the vein (CapillaryLeakTest's tip, 2 mm beside it; 3 ml of continuum bone).
  const std::array<double, 3> centre{o.fieldMm[0] / 2, 21, o.fieldMm[2] / 2};
  const std::array<double, 3> besideVein{centre[0] - 8.5, centre[1] + 5.5, centre[2] - 1};
  const scene::SceneConfig leaking = scene::sceneFromJson({{"tip_mm", besideVein},
                                                          {"direction", {0.5, -0.866, 0}},
                                                          {"volume_ml", 3},
                                                          {"flow_rate_ml_per_s", 0.05},
                                                          {"viscosity_pa_s", 100},
                                                          {"bone_model", "continuum"},
                                                          {"snapshot_interval_s", 1000}});
  const scene::InjectionRunResult a = scene::runInjection(v.ct, leaking, {}), b = scene::runInjection(copy, leaking, {});
  // The cement voxels (fill >= 0.5) by their physical centres, to 0.01 mm.
  auto cement = [](const scene::InjectionRunResult& r) {
    std::set<std::array<long, 3>> voxels;
    auto* fill = r.particles->GetPointData()->GetArray("fill_fraction");
    for (vtkIdType i = 0; i < r.particles->GetNumberOfPoints(); ++i) {
      if (fill->GetTuple1(i) < 0.5) continue;
      const double* x = r.particles->GetPoint(i);
      voxels.insert({std::lround(x[0] * 100), std::lround(x[1] * 100), std::lround(x[2] * 100)});
    }
    return voxels;
  };
  const auto ca = cement(a), cb = cement(b);
  std::size_t both = 0;
  for (const auto& x : ca) both += cb.count(x);
  const double dice = 2.0 * double(both) / double(ca.size() + cb.size());
  const double pa = a.metrics.at("max_tip_pressure_pa").get<double>(), pb = b.metrics.at("max_tip_pressure_pa").get<double>();
  const double la = a.metrics.at("leakage_volume_ml").get<double>(), lb = b.metrics.at("leakage_volume_ml").get<double>();
  const auto venous = [](const scene::InjectionRunResult& r) {
    return r.metrics.at("leakage_by_class").at("volume_ml_by_kind").at("venous").get<double>();
  };
  std::cout << "injection beside the vein, axial / copy: tip " << pa << " / " << pb << " Pa, leakage " << la << " / " << lb
            << " ml (venous " << venous(a) << " / " << venous(b) << "), cement Dice " << dice << " over " << ca.size()
            << " voxels, orientation " << b.metrics.at("ct_orientation") << "\n";
  EXPECT_EQ(b.metrics.at("ct_orientation"), "reoriented");
  ASSERT_GT(la, 1.5e-3) << "the tip no longer reaches the vein: the test's geometry is off";
  EXPECT_NEAR(pb, pa, 0.02 * pa);
  EXPECT_NEAR(lb, la, 1.5e-3);
  EXPECT_NEAR(venous(b), venous(a), 1.5e-3);
  EXPECT_GE(dice, 0.95);

  const planning::PlanRequest r = request(o);
  const planning::PlanResult axial = planning::planInjection(v.ct, r), plan = planning::planInjection(copy, r);
  std::cout << "plan, axial / copy: best depth " << axial.best.depthMm << " / " << plan.best.depthMm << " mm, volume "
            << axial.best.volumeMl << " / " << plan.best.volumeMl << " ml, coverage " << axial.best.coverage << " / "
            << plan.best.coverage << ", syringe " << axial.best.syringeMpa << " / " << plan.best.syringeMpa
            << " MPa, leakage " << axial.best.leakageMl << " / " << plan.best.leakageMl << " ml\n";
  ASSERT_TRUE(axial.best.failure.empty()) << axial.best.failure;
  EXPECT_TRUE(plan.best.failure.empty()) << plan.best.failure;
  EXPECT_EQ(plan.trajectory.verdict, axial.trajectory.verdict) << plan.trajectory.message;
  EXPECT_NEAR(plan.best.depthMm, axial.best.depthMm, 0.25);
  EXPECT_NEAR(plan.best.volumeMl, axial.best.volumeMl, 0.05);
  EXPECT_NEAR(plan.best.coverage, axial.best.coverage, 0.01);
  EXPECT_NEAR(plan.best.syringeMpa, axial.best.syringeMpa, 0.02 * axial.best.syringeMpa);
  EXPECT_NEAR(plan.best.leakageMl, axial.best.leakageMl, 1.5e-3);
}
