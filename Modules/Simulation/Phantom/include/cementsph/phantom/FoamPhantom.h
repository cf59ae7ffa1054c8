// A synthetic open-cell foam CT (issue 4; Basafa et al. 2013, "Foam Block Tests": open-cell foam blocks with
// the pores filled with butter, CT at 0.47 x 0.47 x 0.5 mm) and the matching post-injection CT.
//
// Foam: seeds on a jittered grid (one seed, uniformly placed, per cube of edge cell_size_mm; seeded). A point
// is on a strut (an edge of the seeds' Voronoi diagram) when d3 - d1 < band, d1 <= d2 <= d3 the distances to
// its three nearest seeds (searched among the 27 neighbouring grid cubes); d3 - d1 < band implies d2 - d1 <
// band. With a target porosity the band is solved exactly: it is the (1 - porosity) quantile of d3 - d1 over
// the block's sub-samples. Each voxel is the mean of supersample^3 sub-samples (partial volume): HU = fat +
// f (strut - fat), f the strut fraction; an optional shell (plexiglass) of shell_mm surrounds the block (a
// sub-sample outside the block is shell), then an air margin (air_margin_mm). Then Gaussian noise (sigma noise_hu, seeded), HU rounded to
// integers. Physical frame: origin at the first voxel centre, mm, identity direction.
//
// Post: an injection (InjectionRunner, every numeric choice pinned by PhantomNumerics.h, the tip at the block
// centre moved to the nearest pore voxel, direction +z) on the pre CT; cement (cement_hu) replaces the voxel where the simulated CT's
// rho_fluid / rho0 >= cement_threshold; then a known affine misalignment (post(y) = cemented(A^-1 y), trilinear,
// air outside) and fresh noise (seed + 1).
#pragma once

#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/phantom/PhantomNumerics.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <optional>

namespace cementsph::phantom {

struct FoamOptions {
  std::array<double, 3> sizeMm{30, 30, 30};      // the foam block (without the shell)
  std::array<double, 3> spacingMm{0.47, 0.47, 0.5};
  double cellSizeMm = 4.0;                       // Voronoi cell size (seed grid pitch)
  std::optional<double> porosity = 0.8;          // target; the band is solved (exclusive with strutThicknessMm)
  std::optional<double> strutThicknessMm;        // fixed band d3 - d1 < t, when no target porosity
  double shellMm = 5.0;                          // 0: no shell
  double airMarginMm = 2.0;                      // air (airHu) around the shell, so a misaligned scan stays in air
  double noiseHu = 20.0;                         // Gaussian sigma; 0: none
  std::uint64_t seed = 1;
  int supersample = 3;                           // sub-samples per voxel edge
  double strutHu = 600.0, fatHu = -100.0, shellHu = 120.0, airHu = -1000.0;
  // Throws std::invalid_argument with one line naming the option.
  void validate() const;
};

struct FoamResult {
  imaging::ImageType::Pointer clean;    // without noise
  imaging::ImageType::Pointer ct;       // with noise (rounded to integer HU)
  double bandMm = 0;                    // the strut band t used
  double realisedPorosity = 0;          // 1 - mean strut fraction over the block's voxels (noise-free)
  std::size_t blockVoxels = 0, shellVoxels = 0; // wholly in the block; the others (shell, air)
  std::array<double, 3> blockMinMm{}, blockMaxMm{}; // the block's faces, physical mm
  nlohmann::json toJson() const;        // figures, every key naming its unit
};

FoamResult makeFoam(const FoamOptions& options);

// y = M (x - centre) + centre + translation, M = Rz Ry Rx S (rotation degrees, per-axis scale).
struct AffineParameters {
  std::array<double, 3> rotationDeg{2.0, -1.0, 1.5};
  std::array<double, 3> scale{1.01, 0.99, 1.0};
  std::array<double, 3> translationMm{1.0, -0.5, 0.7};
  std::array<double, 3> centreMm{0, 0, 0};          // set to the volume centre by makePost
  std::array<double, 9> matrix() const;             // row-major M
  std::array<double, 3> apply(const std::array<double, 3>& x) const;
  std::array<double, 3> applyInverse(const std::array<double, 3>& y) const;
};

struct PostOptions {
  double volumeMl = 1.0;
  double viscosityPaS = 100.0;
  double flowRateMlPerS = 0.05;
  double cementHu = 3000.0;
  double cementThreshold = 0.5;  // rho_fluid / rho0
  AffineParameters misalignment;
  PhantomNumerics numerics; // the injection's model and numerics, all pinned
  bool progress = false;
  // Throws std::invalid_argument with one line naming the option.
  void validate() const;
};

struct PostResult {
  imaging::ImageType::Pointer ct;
  std::array<double, 3> requestedTipMm{}, tipMm{}; // block centre; the pore voxel used
  double cementVolumeMl = 0;                        // voxels made cement x voxel volume (before misalignment)
  std::size_t cementVoxels = 0;
  nlohmann::json injectionMetrics;
  nlohmann::json scene;                             // the injection's scene as run (scene::toJson)
  AffineParameters misalignment;                    // with its centre
};

// The nearest voxel centre to `pointMm` whose 3x3x3 neighbourhood is pure pore in `clean` (HU < fatHu + 1),
// block voxels only. Throws std::runtime_error when there is none.
std::array<double, 3> nearestPoreMm(const FoamResult& foam, const FoamOptions& options,
                                    const std::array<double, 3>& pointMm);

// Trilinear resampling of `image` through the affine: out(y) = image(A^-1 y) on image's grid; outside -> value.
imaging::ImageType::Pointer misalign(const imaging::ImageType* image, const AffineParameters& a, float outside);

PostResult makePost(const FoamResult& foam, const FoamOptions& foamOptions, const PostOptions& options);

} // namespace cementsph::phantom
