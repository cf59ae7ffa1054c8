// imaging-bench: the issue-3 speed figures on this machine.
//  1. Registration of ~128^3 pairs with a known affine and cement in the moving image: ours (time,
//     TRE over the region's corners) side by side with elastix on the same files and the same cement
//     mask (when `elastix` is on PATH): its default affine parameter map, then two tighter maps (its speed
//     against its error), and ours without the cement mask. --elastix-map=FILE replaces the default map,
//     --elastix-no-mask gives elastix no mask.
//  2. Surface metrics between two ~100k-vertex surfaces (both directions).
//  3. A whole `cementsph compare` on an 85x85x80 region of 0.47x0.47x0.5 mm voxels.
// Usage: imaging-bench [work-dir] [--quick] [--only=surfaces|compare|registration]. Prints Markdown.
#include "SyntheticVolumes.h"
#include "cementsph/imaging/AffineRegistration.h"
#include "cementsph/imaging/VolumeIO.h"
#include "cementsph/surfacemetrics/Isosurface.h"
#include "cementsph/surfacemetrics/SurfaceDistance.h"

#include <itkImageFileWriter.h>
#include <itkMetaImageIO.h>

#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using namespace cementsph;
using namespace cementsph::testing;

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// elastix's default affine parameter map (elastix::ParameterObject::GetDefaultParameterMap
// ("affine"), as in SimpleElastix / itk-elastix), without writing the result image.
const char* kElastixAffine = R"((FixedInternalImagePixelType "float")
(MovingInternalImagePixelType "float")
(FixedImageDimension 3)
(MovingImageDimension 3)
(UseDirectionCosines "true")
(Registration "MultiResolutionRegistration")
(Interpolator "LinearInterpolator")
(ResampleInterpolator "FinalBSplineInterpolator")
(Resampler "DefaultResampler")
(FixedImagePyramid "FixedSmoothingImagePyramid")
(MovingImagePyramid "MovingSmoothingImagePyramid")
(Optimizer "AdaptiveStochasticGradientDescent")
(Transform "AffineTransform")
(Metric "AdvancedMattesMutualInformation")
(AutomaticScalesEstimation "true")
(AutomaticTransformInitialization "true")
(HowToCombineTransforms "Compose")
(NumberOfHistogramBins 32)
(ErodeMask "false")
(NumberOfResolutions 4)
(MaximumNumberOfIterations 256)
(NumberOfSpatialSamples 2048)
(NewSamplesEveryIteration "true")
(ImageSampler "RandomCoordinate")
(BSplineInterpolationOrder 1)
(FinalBSplineInterpolationOrder 3)
(DefaultPixelValue 0)
(WriteResultImage "false")
(ResultImagePixelType "float")
(ResultImageFormat "mha")
)";

// Reads "(Name v1 v2 ...)" from an elastix TransformParameters file.
std::vector<double> elastixValues(const std::string& file, const std::string& name) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("(" + name + " ", 0) != 0) continue;
    std::istringstream values(line.substr(name.size() + 2));
    std::vector<double> v;
    double x;
    while (values >> x) v.push_back(x);
    return v;
  }
  return {};
}

struct Affine12 {
  std::vector<double> p, c; // 9 matrix + 3 translation; centre
  Vec3 operator()(const Vec3& x) const {
    Vec3 y;
    for (int r = 0; r < 3; ++r) {
      y[r] = c[r] + p[9 + r];
      for (int k = 0; k < 3; ++k) y[r] += p[3 * r + k] * (x[k] - c[k]);
    }
    return y;
  }
};

imaging::RegistrationOptions gOptions; // adjustable from the command line, for tuning runs
std::string gElastixMap; // --elastix-map=FILE: another parameter map, for tuning runs
bool gElastixMask = true; // --elastix-no-mask: elastix sees the cement (as ours does with maskCement off)

// The moving mask ours uses (imaging::cementMetricMask with RegistrationOptions' defaults): 0 on the cement (moving
// above max(fixed) + 100 HU) grown by a 2 mm ball, 1 elsewhere; given to elastix as -mMask so that both
// registrations see the same voxels (without it elastix's metric is dominated by the 3000 HU ball, which
// has nothing to match in the fixed image: 8-9 mm TRE whatever its metric, 2026-12-04).
void writeMovingMask(const ImageType* fixed, const ImageType* moving, const fs::path& file) {
  std::size_t masked = 0;
  using Mask = imaging::MaskType;
  Mask::Pointer mask = imaging::cementMetricMask(fixed, moving, gOptions, masked);
  auto writer = itk::ImageFileWriter<Mask>::New();
  writer->SetImageIO(itk::MetaImageIO::New());
  writer->SetInput(mask);
  writer->SetFileName(file.string());
  writer->Update();
}

// The default map with some entries replaced: {"(Metric ...)", ...} by name.
std::string elastixMapWith(const std::vector<std::pair<std::string, std::string>>& entries) {
  std::string map = kElastixAffine;
  for (const auto& [name, value] : entries) {
    const std::size_t at = map.find("(" + name + " ");
    if (at == std::string::npos) throw std::logic_error("elastix map: no " + name);
    map.replace(at, map.find(')', at) + 1 - at, "(" + name + " " + value + ")");
  }
  return map;
}

// Tighter maps than the default, for elastix's speed against its error (the default map stops far from the
// optimum on these pairs: 2026-12-04, the normalised correlation with 2000 iterations reached 0.005 mm).
// Made when first asked for (a function, not a namespace-scope table: a wrong entry name throws in the run, not
// before main).
const std::vector<std::pair<std::string, std::string>>& tighterElastixMaps() {
  static const std::vector<std::pair<std::string, std::string>> maps = {
    {"normalised correlation, 1000 iterations, 2048 samples",
     elastixMapWith({{"Metric", "\"AdvancedNormalizedCorrelation\""}, {"MaximumNumberOfIterations", "1000"}})},
    {"normalised correlation, 2000 iterations, 8192 samples",
     elastixMapWith({{"Metric", "\"AdvancedNormalizedCorrelation\""}, {"MaximumNumberOfIterations", "2000"},
                     {"NumberOfSpatialSamples", "8192"}})},
  };
  return maps;
}

void runElastix(const fs::path& dir, const ImageType* fixed, const ImageType* moving,
                const RegistrationCase& c, std::string& time, std::string& tre, const std::string& map = "") {
  fs::create_directories(dir);
  imaging::writeVolume(fixed, (dir / "fixed.mha").string());
  imaging::writeVolume(moving, (dir / "moving.mha").string());
  if (gElastixMask) writeMovingMask(fixed, moving, dir / "moving-mask.mha");
  if (!map.empty()) std::ofstream(dir / "affine.txt") << map;
  else if (gElastixMap.empty()) std::ofstream(dir / "affine.txt") << kElastixAffine;
  else fs::copy_file(gElastixMap, dir / "affine.txt", fs::copy_options::overwrite_existing);
  const std::string cmd = "elastix -f " + (dir / "fixed.mha").string() + " -m " + (dir / "moving.mha").string() +
                          (gElastixMask ? " -mMask " + (dir / "moving-mask.mha").string() : std::string()) +
                          " -p " + (dir / "affine.txt").string() + " -out " + dir.string() + " -threads 2 > " +
                          (dir / "stdout.txt").string() + " 2>&1";
  const double t0 = now();
  const int rc = std::system(cmd.c_str());
  const double et = now() - t0;
  const std::string tp = (dir / "TransformParameters.0.txt").string();
  Affine12 a{elastixValues(tp, "TransformParameters"), elastixValues(tp, "CenterOfRotationPoint")};
  if (rc == 0 && a.p.size() == 12 && a.c.size() == 3) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", et);
    time = buf;
    std::snprintf(buf, sizeof buf, "%.3f", cornerTreMm(c.grid, c.truth, a));
    tre = buf;
  } else {
    time = "failed (rc " + std::to_string(rc) + ")";
  }
}

bool haveElastix() { return std::system("command -v elastix > /dev/null 2>&1") == 0; }

bool gElastix = true;
int gPairs = 3;

void benchRegistration(const fs::path& work, unsigned n, double spacing, int pairs) {
  std::cout << "\n### Registration, " << n << "^3 voxels of " << spacing << " x " << spacing << " x "
            << spacing * 1.05 << " mm, cement (9 mm ball, 3000 HU) in the moving image only\n\n";
  std::cout << "| pair | rotation (deg) | scale | shift (mm) | initial TRE (mm) | ours: time (s) | ours: TRE (mm) "
               "| ours, no cement mask: TRE (mm) | elastix: time (s) | elastix: TRE (mm) "
               "| elastix, same pair without cement: time (s) | TRE (mm) |\n"
               "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  const Vec3 rots[3] = {{4, -5, 8}, {-7, 6, -3}, {2, 9, 4}};
  const Vec3 scales[3] = {{1.05, 0.96, 1.03}, {0.95, 1.04, 0.97}, {1.03, 1.02, 0.95}};
  const Vec3 shifts[3] = {{6, -5, 5}, {-4, 7, -6}, {8, 3, -5}};
  const bool elastix = gElastix && haveElastix();
  std::vector<std::string> tighter; // rows of the second table
  for (int i = 0; i < pairs; ++i) {
    const auto c = makeRegistrationCase(n, spacing, rots[i], scales[i], shifts[i], true,
                                        {1, 0, 0, 0, 1, 0, 0, 0, 1}, 11u + static_cast<unsigned>(i));
    const double initial = cornerTreMm(c.grid, c.truth, [](const Vec3& x) { return x; });
    double t0 = now();
    const auto ours = imaging::registerAffine(c.fixed, c.moving, gOptions);
    if (getenv("VERBOSE")) std::cerr << imaging::formatRegistrationReport(ours);
    const double oursTime = now() - t0;
    auto viaItk = [](const imaging::AffineTransformType* t) {
      return [t](const Vec3& x) {
        imaging::PointType p;
        for (unsigned k = 0; k < 3; ++k) p[k] = x[k];
        const auto q = t->TransformPoint(p);
        return Vec3{q[0], q[1], q[2]};
      };
    };
    const double oursTre = cornerTreMm(c.grid, c.truth, viaItk(ours.transform));
    imaging::RegistrationOptions unmasked = gOptions;
    unmasked.maskCement = false;
    const auto plain = imaging::registerAffine(c.fixed, c.moving, unmasked);
    const double plainTre = cornerTreMm(c.grid, c.truth, viaItk(plain.transform));

    std::string elastixTime = "n/a", elastixTre = "n/a", cleanTime = "n/a", cleanTre = "n/a";
    if (elastix) {
      runElastix(work / ("pair" + std::to_string(i)), c.fixed, c.moving, c, elastixTime, elastixTre);
      // The same pair without cement: is a failure the cement's doing or the phantom's?
      const auto clean = makeRegistrationCase(n, spacing, rots[i], scales[i], shifts[i], false,
                                              {1, 0, 0, 0, 1, 0, 0, 0, 1}, 11u + static_cast<unsigned>(i));
      runElastix(work / ("pair" + std::to_string(i) + "-clean"), clean.fixed, clean.moving, clean, cleanTime,
                 cleanTre);
      for (std::size_t m = 0; m < tighterElastixMaps().size() && gElastixMap.empty(); ++m) {
        std::string t = "n/a", e = "n/a";
        runElastix(work / ("pair" + std::to_string(i) + "-map" + std::to_string(m + 1)), c.fixed, c.moving, c, t, e,
                   tighterElastixMaps()[m].second);
        tighter.push_back("| " + std::to_string(i + 1) + " | " + tighterElastixMaps()[m].first + " | " + t + " | " + e + " |");
      }
    }
    char row[400];
    std::snprintf(row, sizeof row,
                  "| %d | %g, %g, %g | %g, %g, %g | %g, %g, %g | %.2f | %.2f | %.3f | %.3f | %s | %s | %s | %s |\n", i + 1,
                  rots[i][0], rots[i][1], rots[i][2], scales[i][0], scales[i][1], scales[i][2],
                  shifts[i][0], shifts[i][1], shifts[i][2], initial, oursTime, oursTre, plainTre,
                  elastixTime.c_str(), elastixTre.c_str(), cleanTime.c_str(), cleanTre.c_str());
    std::cout << row << std::flush;
  }
  if (!tighter.empty()) {
    std::cout << "\n### elastix with tighter parameter maps (the same pairs with cement, the same cement mask)\n\n"
                 "| pair | elastix map (else the default affine map) | elastix: time (s) | elastix: TRE (mm) |\n"
                 "|---|---|---|---|\n";
    for (const auto& r : tighter) std::cout << r << "\n";
  }
}

void benchSurfaces() {
  // Two offset spheres voxelised on a 0.5 mm grid; R ~ 38 and 40 mm gives ~100k vertices each.
  auto sphere = [](double r, double cx) {
    auto image = vtkSmartPointer<vtkImageData>::New();
    const int n = 176;
    image->SetDimensions(n, n, n);
    image->SetSpacing(0.5, 0.5, 0.5);
    image->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
    auto* p = static_cast<unsigned char*>(image->GetScalarPointer());
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const double x = i * 0.5 - cx, y = j * 0.5 - 44, z = k * 0.5 - 44;
          *p++ = x * x + y * y + z * z <= r * r ? 1 : 0;
        }
    return image;
  };
  double t0 = now();
  auto a = surfacemetrics::isosurface(sphere(37.0, 44.0));
  auto b = surfacemetrics::isosurface(sphere(39.0, 45.0));
  const double isoTime = (now() - t0) / 2.0;
  t0 = now();
  const std::clock_t c0 = std::clock();
  const auto cmp = surfacemetrics::compareSurfaces(a, b);
  const double metricTime = now() - t0;
  const double metricCpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  std::cout << "\n### Surface metrics\n\n| vertices (a, b) | isosurface, each (s) | both directed distances + "
               "summaries: wall (s) | same: CPU, all threads (s) | error (mm) | Hausdorff (mm) |\n"
               "|---|---|---|---|---|---|\n";
  std::printf("| %lld, %lld | %.3f | %.3f | %.3f | %.3f | %.3f |\n", static_cast<long long>(a->GetNumberOfPoints()),
              static_cast<long long>(b->GetNumberOfPoints()), isoTime, metricTime, metricCpu, cmp.errorMm,
              cmp.hausdorffMm);
}

void benchCompare(const fs::path& work) {
  CompareCase c; // defaults: a 7 mm cement ball, the simulation 7.5 mm and 0.8 mm off
  c.grid.size = {85, 85, 80};
  c.grid.spacing = {0.47, 0.47, 0.5};
  c.grid.origin = {-19.74, -19.74, -19.75};
  const fs::path dir = work / "compare";
  fs::create_directories(dir);
  const Vec3 tip = writeCompareCase(c, dir.string());
  char point[96];
  std::snprintf(point, sizeof point, "%.3f,%.3f,%.3f", tip[0], tip[1], tip[2]);
  const std::string cmd = std::string(CEMENTSPH_EXE) + " compare --pre " + (dir / "pre.nrrd").string() +
                          " --post " + (dir / "post.nrrd").string() + " --simulated " +
                          (dir / "sim.nrrd").string() + " --injection-point-mm " + point + " --out " +
                          (dir / "out").string() + " > " + (dir / "stdout.txt").string() + " 2>&1";
  const double t0 = now();
  const int rc = std::system(cmd.c_str());
  const double t = now() - t0;
  std::cout << "\n### Whole `cementsph compare`, 85 x 85 x 80 voxels of 0.47 x 0.47 x 0.5 mm, with a "
               "simulated CT\n\n| exit code | wall time (s) |\n|---|---|\n";
  std::printf("| %d | %.2f |\n", rc, t);
  std::cout << "\n(summary printed by the command:)\n\n```\n" << std::ifstream(dir / "stdout.txt").rdbuf()
            << "```\n";
}

} // namespace

namespace {
int run(int argc, char** argv) {
  fs::path work = fs::temp_directory_path() / "cementsph-imaging-bench";
  bool quick = false;
  std::string only;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") quick = true;
    else if (a.rfind("--only=", 0) == 0) only = a.substr(7);
    else if (a.rfind("--samples=", 0) == 0) gOptions.samplesPerLevel = static_cast<unsigned>(std::stoul(a.substr(10)));
    else if (a.rfind("--line-search=", 0) == 0) gOptions.lineSearchIterations = static_cast<unsigned>(std::stoul(a.substr(14)));
    else if (a.rfind("--convergence=", 0) == 0) gOptions.convergenceValue = std::stod(a.substr(14));
    else if (a.rfind("--pairs=", 0) == 0) gPairs = std::stoi(a.substr(8));
    else if (a.rfind("--max-iterations=", 0) == 0) gOptions.maxIterationsPerLevel = static_cast<unsigned>(std::stoul(a.substr(17)));
    else if (a == "--coarse-affine") { gOptions.affineShrink = {2}; gOptions.affineSigmaVoxels = {1.0}; }
    else if (a == "--no-elastix") gElastix = false;
    else if (a == "--elastix-no-mask") gElastixMask = false;
    else if (a.rfind("--elastix-map=", 0) == 0) {
      gElastixMap = a.substr(14);
      if (!fs::is_regular_file(gElastixMap))
        throw std::invalid_argument("--elastix-map=" + gElastixMap + ": no such file (give an elastix parameter map)");
    } else work = a;
  }
  fs::create_directories(work);
  std::cout << "## Imaging benchmark (imaging-bench)\n";
  if (only.empty() || only == "surfaces") benchSurfaces();
  if (only.empty() || only == "compare") benchCompare(work);
  if (only.empty() || only == "registration")
    benchRegistration(work, quick ? 64 : 128, quick ? 1.5 : 0.8, quick ? 1 : gPairs);
  return 0;
}
} // namespace

// One line and exit status 2 for a bad option or a failed step (a number that does not parse, a missing map),
// not an uncaught exception.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "imaging-bench: " << e.what() << "\n";
    return 2;
  }
}
