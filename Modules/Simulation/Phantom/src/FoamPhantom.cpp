#include "cementsph/phantom/FoamPhantom.h"

#include "cementsph/scene/InjectionRunner.h"
#include "cementsph/scene/SceneConfig.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace cementsph::phantom {

namespace {

using Vec3 = std::array<double, 3>;

imaging::ImageType::Pointer makeImage(const std::array<std::size_t, 3>& n, const Vec3& spacing, const Vec3& origin,
                                      float value) {
  auto image = imaging::ImageType::New();
  imaging::ImageType::RegionType region;
  imaging::ImageType::SpacingType sp;
  imaging::ImageType::PointType org;
  for (unsigned a = 0; a < 3; ++a) {
    region.SetSize(a, n[a]);
    sp[a] = spacing[a];
    org[a] = origin[a];
  }
  image->SetRegions(region);
  image->SetSpacing(sp);
  image->SetOrigin(org);
  image->Allocate();
  image->FillBuffer(value);
  return image;
}

std::array<std::size_t, 3> sizeOf(const imaging::ImageType* image) {
  const auto s = image->GetLargestPossibleRegion().GetSize();
  return {s[0], s[1], s[2]};
}

// Seeds on a jittered grid; the three nearest distances from the 27 neighbouring cells.
struct SeedGrid {
  std::array<int, 3> n{};
  double pitch = 1;
  Vec3 lo{};
  std::vector<Vec3> seeds; // one per cell, x fastest

  SeedGrid(const Vec3& loMm, const Vec3& hiMm, double pitchMm, std::uint64_t seed) : pitch(pitchMm), lo(loMm) {
    for (int a = 0; a < 3; ++a) n[a] = std::max(1, static_cast<int>(std::ceil((hiMm[a] - loMm[a]) / pitch)));
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    seeds.resize(static_cast<std::size_t>(n[0]) * n[1] * n[2]);
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          Vec3& s = seeds[(static_cast<std::size_t>(k) * n[1] + j) * n[0] + i];
          s[0] = lo[0] + (i + u(rng)) * pitch;
          s[1] = lo[1] + (j + u(rng)) * pitch;
          s[2] = lo[2] + (k + u(rng)) * pitch;
        }
  }

  // d3 - d1 at p (cells outside the grid have no seed: the block's faces are cut through cells).
  double band(const Vec3& p) const {
    int c[3];
    for (int a = 0; a < 3; ++a) c[a] = std::clamp(static_cast<int>(std::floor((p[a] - lo[a]) / pitch)), 0, n[a] - 1);
    double d[3] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
                   std::numeric_limits<double>::max()};
    for (int k = std::max(0, c[2] - 1); k <= std::min(n[2] - 1, c[2] + 1); ++k)
      for (int j = std::max(0, c[1] - 1); j <= std::min(n[1] - 1, c[1] + 1); ++j)
        for (int i = std::max(0, c[0] - 1); i <= std::min(n[0] - 1, c[0] + 1); ++i) {
          const Vec3& s = seeds[(static_cast<std::size_t>(k) * n[1] + j) * n[0] + i];
          const double dx = p[0] - s[0], dy = p[1] - s[1], dz = p[2] - s[2];
          const double q = dx * dx + dy * dy + dz * dz;
          if (q < d[2]) {
            if (q < d[1]) {
              d[2] = d[1];
              if (q < d[0]) {
                d[1] = d[0];
                d[0] = q;
              } else {
                d[1] = q;
              }
            } else {
              d[2] = q;
            }
          }
        }
    return std::sqrt(d[2]) - std::sqrt(d[0]);
  }
};

void addNoise(imaging::ImageType* image, double sigma, std::uint64_t seed) {
  float* p = image->GetBufferPointer();
  const std::size_t count = image->GetLargestPossibleRegion().GetNumberOfPixels();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma > 0 ? sigma : 1.0);
  for (std::size_t v = 0; v < count; ++v) {
    const double x = p[v] + (sigma > 0 ? g(rng) : 0.0);
    p[v] = static_cast<float>(std::round(x));
  }
}

bool finitePositive(double x) { return std::isfinite(x) && x > 0; }

} // namespace

void FoamOptions::validate() const {
  for (double s : sizeMm)
    if (!finitePositive(s) || s > 500) throw std::invalid_argument("size_mm must be in (0, 500]");
  for (double s : spacingMm)
    if (!finitePositive(s)) throw std::invalid_argument("spacing_mm must be > 0");
  if (!finitePositive(cellSizeMm) || cellSizeMm > 100) throw std::invalid_argument("cell_size_mm must be in (0, 100]");
  if (porosity && strutThicknessMm)
    throw std::invalid_argument("give a target porosity or a strut thickness, not both");
  if (!porosity && !strutThicknessMm) throw std::invalid_argument("give a target porosity or a strut thickness");
  if (porosity && !(std::isfinite(*porosity) && *porosity > 0 && *porosity < 1))
    throw std::invalid_argument("porosity must be in (0, 1)");
  if (strutThicknessMm && !(finitePositive(*strutThicknessMm) && *strutThicknessMm < cellSizeMm))
    throw std::invalid_argument("strut_thickness_mm must be in (0, cell_size_mm)");
  if (!(std::isfinite(shellMm) && shellMm >= 0 && shellMm <= 50)) throw std::invalid_argument("shell_mm must be in [0, 50]");
  if (!(std::isfinite(airMarginMm) && airMarginMm >= 0 && airMarginMm <= 50))
    throw std::invalid_argument("air_margin_mm must be in [0, 50]");
  if (!(std::isfinite(noiseHu) && noiseHu >= 0 && noiseHu <= 1000)) throw std::invalid_argument("noise_hu must be in [0, 1000]");
  if (supersample < 1 || supersample > 8) throw std::invalid_argument("supersample must be in [1, 8]");
  std::size_t voxels = 1;
  for (int a = 0; a < 3; ++a) voxels *= static_cast<std::size_t>(std::ceil((sizeMm[a] + 2 * shellMm + 2 * airMarginMm) / spacingMm[a]));
  if (voxels > 64'000'000) throw std::invalid_argument("size_mm: the volume would exceed 64 million voxels");
}

nlohmann::json FoamResult::toJson() const {
  return {{"strut_band_mm", bandMm},
          {"realised_porosity", realisedPorosity},
          {"block_voxels", blockVoxels},
          {"non_block_voxels", shellVoxels},
          {"block_min_mm", blockMinMm},
          {"block_max_mm", blockMaxMm}};
}

FoamResult makeFoam(const FoamOptions& o) {
  o.validate();
  FoamResult r;
  std::array<std::size_t, 3> n{};
  Vec3 origin{};
  for (int a = 0; a < 3; ++a) {
    const double total = o.sizeMm[a] + 2 * o.shellMm + 2 * o.airMarginMm;
    n[a] = std::max<std::size_t>(2, static_cast<std::size_t>(std::llround(total / o.spacingMm[a])));
    origin[a] = 0.5 * o.spacingMm[a]; // voxel (0,0,0) covers [0, spacing)
    const double extent = static_cast<double>(n[a]) * o.spacingMm[a];
    r.blockMinMm[a] = 0.5 * (extent - o.sizeMm[a]);
    r.blockMaxMm[a] = r.blockMinMm[a] + o.sizeMm[a];
  }
  const SeedGrid grid(r.blockMinMm, r.blockMaxMm, o.cellSizeMm, o.seed);
  const int ss = o.supersample;
  const std::size_t perVoxel = static_cast<std::size_t>(ss) * ss * ss;
  const std::size_t count = n[0] * n[1] * n[2];
  // band value of every sub-sample; +inf marks the shell (never strut), NaN never occurs.
  std::vector<float> f(count * perVoxel);
  const long long nz = static_cast<long long>(n[2]);
#pragma omp parallel for schedule(dynamic)
  for (long long k = 0; k < nz; ++k)
    for (std::size_t j = 0; j < n[1]; ++j)
      for (std::size_t i = 0; i < n[0]; ++i) {
        const std::size_t v = (static_cast<std::size_t>(k) * n[1] + j) * n[0] + i;
        std::size_t s = 0;
        for (int c = 0; c < ss; ++c)
          for (int b = 0; b < ss; ++b)
            for (int a = 0; a < ss; ++a, ++s) {
              const Vec3 p{(static_cast<double>(i) + (a + 0.5) / ss) * o.spacingMm[0],
                           (static_cast<double>(j) + (b + 0.5) / ss) * o.spacingMm[1],
                           (static_cast<double>(k) + (c + 0.5) / ss) * o.spacingMm[2]};
              bool inBlock = true;
              for (int x = 0; x < 3; ++x) inBlock = inBlock && p[x] >= r.blockMinMm[x] && p[x] < r.blockMaxMm[x];
              bool inShell = true;
              for (int x = 0; x < 3; ++x)
                inShell = inShell && p[x] >= r.blockMinMm[x] - o.shellMm && p[x] < r.blockMaxMm[x] + o.shellMm;
              f[v * perVoxel + s] = inBlock   ? static_cast<float>(grid.band(p))
                                    : inShell ? std::numeric_limits<float>::infinity()
                                              : -std::numeric_limits<float>::infinity();
            }
      }
  // The band: given, or the (1 - porosity) quantile of the block's sub-samples.
  if (o.porosity) {
    std::vector<float> block;
    block.reserve(f.size());
    for (float x : f)
      if (std::isfinite(x)) block.push_back(x);
    if (block.empty()) throw std::invalid_argument("size_mm: the block has no sub-samples");
    const std::size_t q = std::min(block.size() - 1, static_cast<std::size_t>(std::llround((1.0 - *o.porosity) *
                                                                                            static_cast<double>(block.size()))));
    std::nth_element(block.begin(), block.begin() + static_cast<std::ptrdiff_t>(q), block.end());
    r.bandMm = block[q]; // f < band is strut: exactly q sub-samples (ties aside)
  } else {
    r.bandMm = *o.strutThicknessMm;
  }
  r.clean = makeImage(n, o.spacingMm, origin, 0.0f);
  float* out = r.clean->GetBufferPointer();
  double strutSum = 0;
  for (std::size_t v = 0; v < count; ++v) {
    std::size_t strut = 0, shell = 0, air = 0;
    for (std::size_t s = 0; s < perVoxel; ++s) {
      const float x = f[v * perVoxel + s];
      if (x == std::numeric_limits<float>::infinity()) ++shell;
      else if (x == -std::numeric_limits<float>::infinity()) ++air;
      else if (x < r.bandMm) ++strut;
    }
    const double fs = static_cast<double>(strut) / static_cast<double>(perVoxel);
    const double fsh = static_cast<double>(shell) / static_cast<double>(perVoxel);
    const double fa = static_cast<double>(air) / static_cast<double>(perVoxel);
    out[v] = static_cast<float>(o.fatHu * (1.0 - fs - fsh - fa) + o.strutHu * fs + o.shellHu * fsh + o.airHu * fa);
    if (shell + air == 0) {
      ++r.blockVoxels;
      strutSum += fs;
    } else {
      ++r.shellVoxels;
    }
  }
  r.realisedPorosity = r.blockVoxels ? 1.0 - strutSum / static_cast<double>(r.blockVoxels) : 1.0;
  r.ct = makeImage(n, o.spacingMm, origin, 0.0f);
  std::copy(out, out + count, r.ct->GetBufferPointer());
  addNoise(r.ct, o.noiseHu, o.seed);
  return r;
}

std::array<double, 9> AffineParameters::matrix() const {
  const double d = M_PI / 180.0;
  const double cx = std::cos(rotationDeg[0] * d), sx = std::sin(rotationDeg[0] * d);
  const double cy = std::cos(rotationDeg[1] * d), sy = std::sin(rotationDeg[1] * d);
  const double cz = std::cos(rotationDeg[2] * d), sz = std::sin(rotationDeg[2] * d);
  const double Rx[9] = {1, 0, 0, 0, cx, -sx, 0, sx, cx};
  const double Ry[9] = {cy, 0, sy, 0, 1, 0, -sy, 0, cy};
  const double Rz[9] = {cz, -sz, 0, sz, cz, 0, 0, 0, 1};
  auto mul = [](const double* A, const double* B) {
    std::array<double, 9> C{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) C[3 * i + j] += A[3 * i + k] * B[3 * k + j];
    return C;
  };
  const auto zy = mul(Rz, Ry);
  const auto r = mul(zy.data(), Rx);
  std::array<double, 9> m{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[3 * i + j] = r[3 * i + j] * scale[j];
  return m;
}

std::array<double, 3> AffineParameters::apply(const std::array<double, 3>& x) const {
  const auto m = matrix();
  std::array<double, 3> y{};
  for (int i = 0; i < 3; ++i) {
    y[i] = centreMm[i] + translationMm[i];
    for (int j = 0; j < 3; ++j) y[i] += m[3 * i + j] * (x[j] - centreMm[j]);
  }
  return y;
}

std::array<double, 3> AffineParameters::applyInverse(const std::array<double, 3>& y) const {
  const auto m = matrix();
  const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                     m[2] * (m[3] * m[7] - m[4] * m[6]);
  const std::array<double, 9> inv{(m[4] * m[8] - m[5] * m[7]) / det, (m[2] * m[7] - m[1] * m[8]) / det,
                                  (m[1] * m[5] - m[2] * m[4]) / det, (m[5] * m[6] - m[3] * m[8]) / det,
                                  (m[0] * m[8] - m[2] * m[6]) / det, (m[2] * m[3] - m[0] * m[5]) / det,
                                  (m[3] * m[7] - m[4] * m[6]) / det, (m[1] * m[6] - m[0] * m[7]) / det,
                                  (m[0] * m[4] - m[1] * m[3]) / det};
  std::array<double, 3> x{};
  for (int i = 0; i < 3; ++i) {
    x[i] = centreMm[i];
    for (int j = 0; j < 3; ++j) x[i] += inv[3 * i + j] * (y[j] - centreMm[j] - translationMm[j]);
  }
  return x;
}

imaging::ImageType::Pointer misalign(const imaging::ImageType* image, const AffineParameters& a, float outside) {
  const auto n = sizeOf(image);
  Vec3 sp{}, org{};
  for (unsigned x = 0; x < 3; ++x) {
    sp[x] = image->GetSpacing()[x];
    org[x] = image->GetOrigin()[x];
  }
  auto result = makeImage(n, sp, org, outside);
  const float* in = image->GetBufferPointer();
  float* out = result->GetBufferPointer();
  const long long nz = static_cast<long long>(n[2]);
#pragma omp parallel for schedule(static)
  for (long long k = 0; k < nz; ++k)
    for (std::size_t j = 0; j < n[1]; ++j)
      for (std::size_t i = 0; i < n[0]; ++i) {
        const Vec3 y{org[0] + static_cast<double>(i) * sp[0], org[1] + static_cast<double>(j) * sp[1],
                     org[2] + static_cast<double>(k) * sp[2]};
        const Vec3 x = a.applyInverse(y);
        double c[3];
        long long c0[3];
        bool inside = true;
        for (int d = 0; d < 3; ++d) {
          c[d] = (x[d] - org[d]) / sp[d];
          c0[d] = static_cast<long long>(std::floor(c[d]));
          inside = inside && c[d] >= 0 && c[d] <= static_cast<double>(n[d] - 1);
          c0[d] = std::clamp<long long>(c0[d], 0, static_cast<long long>(n[d]) - 2);
        }
        if (!inside) continue;
        double value = 0;
        for (int dz = 0; dz < 2; ++dz)
          for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) {
              const double fx = c[0] - static_cast<double>(c0[0]), fy = c[1] - static_cast<double>(c0[1]),
                           fz = c[2] - static_cast<double>(c0[2]);
              const double w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz);
              const std::size_t v = (static_cast<std::size_t>(c0[2] + dz) * n[1] + static_cast<std::size_t>(c0[1] + dy)) *
                                        n[0] + static_cast<std::size_t>(c0[0] + dx);
              value += w * in[v];
            }
        out[(static_cast<std::size_t>(k) * n[1] + j) * n[0] + i] = static_cast<float>(value);
      }
  return result;
}

std::array<double, 3> nearestPoreMm(const FoamResult& foam, const FoamOptions& o, const std::array<double, 3>& p) {
  const imaging::ImageType* img = foam.clean;
  const auto n = sizeOf(img);
  const float* v = img->GetBufferPointer();
  const float pore = static_cast<float>(o.fatHu + 1.0);
  auto at = [&](std::size_t i, std::size_t j, std::size_t k) { return v[(k * n[1] + j) * n[0] + i]; };
  double best = std::numeric_limits<double>::max();
  std::array<double, 3> bestMm{};
  for (std::size_t k = 1; k + 1 < n[2]; ++k)
    for (std::size_t j = 1; j + 1 < n[1]; ++j)
      for (std::size_t i = 1; i + 1 < n[0]; ++i) {
        const std::array<double, 3> c{img->GetOrigin()[0] + static_cast<double>(i) * o.spacingMm[0],
                                      img->GetOrigin()[1] + static_cast<double>(j) * o.spacingMm[1],
                                      img->GetOrigin()[2] + static_cast<double>(k) * o.spacingMm[2]};
        const double d2 = (c[0] - p[0]) * (c[0] - p[0]) + (c[1] - p[1]) * (c[1] - p[1]) + (c[2] - p[2]) * (c[2] - p[2]);
        if (d2 >= best) continue;
        bool ok = true;
        for (int dz = -1; dz <= 1 && ok; ++dz)
          for (int dy = -1; dy <= 1 && ok; ++dy)
            for (int dx = -1; dx <= 1 && ok; ++dx)
              ok = at(i + static_cast<std::size_t>(dx), j + static_cast<std::size_t>(dy), k + static_cast<std::size_t>(dz)) < pore;
        if (!ok) continue;
        for (int x = 0; x < 3; ++x) ok = ok && c[x] > foam.blockMinMm[x] && c[x] < foam.blockMaxMm[x];
        if (!ok) continue;
        best = d2;
        bestMm = c;
      }
  if (best == std::numeric_limits<double>::max()) throw std::runtime_error("the foam block has no pore voxel");
  return bestMm;
}

void PostOptions::validate() const {
  if (!(finitePositive(volumeMl) && volumeMl <= 20)) throw std::invalid_argument("volume_ml must be in (0, 20]");
  if (!(finitePositive(viscosityPaS) && viscosityPaS <= 1e5))
    throw std::invalid_argument("viscosity_pa_s must be in (0, 1e5]");
  if (!(finitePositive(flowRateMlPerS) && flowRateMlPerS <= 10))
    throw std::invalid_argument("flow_rate_ml_per_s must be in (0, 10]");
  if (!(cementThreshold > 0 && cementThreshold < 10)) throw std::invalid_argument("cement_threshold must be in (0, 10)");
}

PostResult makePost(const FoamResult& foam, const FoamOptions& fo, const PostOptions& po) {
  po.validate();
  PostResult r;
  for (int a = 0; a < 3; ++a) r.requestedTipMm[a] = 0.5 * (foam.blockMinMm[a] + foam.blockMaxMm[a]);
  r.tipMm = nearestPoreMm(foam, fo, r.requestedTipMm);

  checkModelPreset(po.numerics);
  const scene::SceneConfig sc =
      phantomInjectionScene(po.numerics, r.tipMm, po.volumeMl, po.viscosityPaS, po.flowRateMlPerS);
  r.scene = scene::toJson(sc);
  scene::InjectionRunOptions ro;
  ro.progress = po.progress;
  ro.huPerRelativeDensity = po.numerics.huPerRelativeDensity;
  const auto run = scene::runInjection(foam.ct, sc, ro);
  r.injectionMetrics = run.metrics;

  // Cement replaces the voxel where rho_fluid / rho0 >= threshold (sim - pre = k rho/rho0 on the ROI).
  auto cemented = makeImage(sizeOf(foam.clean), fo.spacingMm,
                            {foam.clean->GetOrigin()[0], foam.clean->GetOrigin()[1], foam.clean->GetOrigin()[2]}, 0.0f);
  const auto n = sizeOf(foam.clean);
  std::copy(foam.clean->GetBufferPointer(), foam.clean->GetBufferPointer() + n[0] * n[1] * n[2],
            cemented->GetBufferPointer());
  const imaging::ImageType* sim = run.simulatedCt;
  const auto rn = sizeOf(sim);
  const float* sv = sim->GetBufferPointer();
  for (std::size_t k = 0; k < rn[2]; ++k)
    for (std::size_t j = 0; j < rn[1]; ++j)
      for (std::size_t i = 0; i < rn[0]; ++i) {
        imaging::ImageType::IndexType ri{{static_cast<long>(i), static_cast<long>(j), static_cast<long>(k)}};
        imaging::ImageType::PointType p;
        sim->TransformIndexToPhysicalPoint(ri, p);
        imaging::ImageType::IndexType ci;
        if (!foam.ct->TransformPhysicalPointToIndex(p, ci)) continue;
        const double rel = (sv[(k * rn[1] + j) * rn[0] + i] - foam.ct->GetPixel(ci)) / po.numerics.huPerRelativeDensity;
        if (rel >= po.cementThreshold) {
          cemented->SetPixel(ci, static_cast<float>(po.cementHu));
          ++r.cementVoxels;
        }
      }
  r.cementVolumeMl = static_cast<double>(r.cementVoxels) * fo.spacingMm[0] * fo.spacingMm[1] * fo.spacingMm[2] * 1e-3;
  r.misalignment = po.misalignment;
  for (int a = 0; a < 3; ++a)
    r.misalignment.centreMm[a] = foam.clean->GetOrigin()[a] + 0.5 * static_cast<double>(n[a] - 1) * fo.spacingMm[a];
  r.ct = misalign(cemented, r.misalignment, static_cast<float>(fo.airHu));
  addNoise(r.ct, fo.noiseHu, fo.seed + 1);
  return r;
}

} // namespace cementsph::phantom
