// Synthetic CT volumes for the imaging tests and the benchmark, made in code (nothing downloaded).
// The phantom is an analytic function of physical position (mm), so a volume "moved" by a known
// affine is sampled exactly, without interpolation error: moving(y) = phantom(A^-1 y).
#pragma once

#include "cementsph/imaging/ImageTypes.h"

#include <array>
#include <functional>
#include <vector>

namespace cementsph::testing {

using imaging::ImageType;
using Vec3 = std::array<double, 3>;

// A bone block: an ellipsoidal cortical shell (~1200 HU) around trabecular texture (Gaussian blobs of
// both signs over marrow at ~0 HU), in air (-1000 HU). Blobs vary along all three axes.
class BonePhantom {
public:
  explicit BonePhantom(const Vec3& centreMm, const Vec3& semiAxesMm, unsigned seed = 7,
                       int blobs = 60);
  double valueAt(const Vec3& pMm) const;
  double maximumHU() const { return 1600.0; } // upper bound of valueAt

private:
  struct Blob {
    Vec3 centre;
    double sigma, amplitude;
  };
  Vec3 centre_, semi_;
  std::vector<Blob> blobs_;
};

// y = M (x - centre) + centre + translation.
struct Affine {
  std::array<double, 9> matrix{1, 0, 0, 0, 1, 0, 0, 0, 1};
  Vec3 centre{0, 0, 0};
  Vec3 translation{0, 0, 0};
  Vec3 apply(const Vec3& x) const;
  Affine inverse() const;
  // Rotation about z, y, x (degrees, applied x first), then per-axis scale first: M = R S.
  static Affine fromParameters(const Vec3& rotationDeg, const Vec3& scale, const Vec3& translationMm,
                               const Vec3& centreMm);
};

struct Grid {
  std::array<unsigned, 3> size{64, 64, 64};
  Vec3 spacing{1, 1, 1};
  Vec3 origin{0, 0, 0};
  std::array<double, 9> direction{1, 0, 0, 0, 1, 0, 0, 0, 1};
};

ImageType::Pointer makeImage(const Grid& grid, float value = 0.0f);

// Samples phantom(A^-1 y) at every voxel centre y; optionally adds a bright "cement" ball
// (cementHU, radius in mm, centre in the image's physical space) that replaces the tissue.
struct CementBall {
  Vec3 centreMm{0, 0, 0};
  double radiusMm = 0.0;
  double hu = 3000.0;
};
ImageType::Pointer sample(const BonePhantom& phantom, const Grid& grid, const Affine& toImage = {},
                          const CementBall& cement = {});

// Root-mean-square distance between estimate(c) and truth(c) over the 8 corners c of the grid's
// region (the target registration error the tests use).
double cornerTreMm(const Grid& grid, const Affine& truth,
                   const std::function<Vec3(const Vec3&)>& estimate);

Vec3 gridCentre(const Grid& grid);

// A registration problem with a known answer: fixed = phantom on an n^3 grid (z spacing 5 % larger,
// so the voxels are anisotropic), moving = phantom moved by `truth` on the same grid, optionally
// with a 9 mm ball of 3000 HU "cement" inside the moved bone. The registration should find a
// transform equal to truth (fixed points -> moving points).
struct RegistrationCase {
  Grid grid;
  Affine truth;
  ImageType::Pointer fixed, moving;
};
RegistrationCase makeRegistrationCase(unsigned n, double spacingMm, const Vec3& rotationDeg,
                                      const Vec3& scale, const Vec3& translationMm, bool cement,
                                      const std::array<double, 9>& direction = {1, 0, 0, 0, 1, 0, 0, 0, 1},
                                      unsigned seed = 7);

// A case for `cementsph compare`, written into a directory: pre.nrrd (the phantom), post.nrrd (the
// phantom moved by rotation/scale/translation, with a 3000 HU cement ball of cementRadiusMm at the
// moved injection point) and sim.nrrd (on pre's grid: a 2500 HU ball of simRadiusMm, simOffsetMm
// along x from the injection point). The injection point is 1 mm off the grid centre.
struct CompareCase {
  Grid grid;
  Vec3 semiAxesMm{17, 16, 17};
  unsigned seed = 5;
  Vec3 rotationDeg{3, -2, 4}, scale{1.01, 0.99, 1.0}, translationMm{2.0, -1.5, 1.0};
  double cementRadiusMm = 7.0, simRadiusMm = 7.5, simOffsetMm = 0.8;
};
// Returns the injection point (mm, pre's space).
Vec3 writeCompareCase(const CompareCase& c, const std::string& directory);

} // namespace cementsph::testing
