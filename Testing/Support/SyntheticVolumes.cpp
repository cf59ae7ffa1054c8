#include "SyntheticVolumes.h"

#include <algorithm>
#include "cementsph/imaging/VolumeIO.h"

#include <cmath>
#include <random>

namespace cementsph::testing {

BonePhantom::BonePhantom(const Vec3& centreMm, const Vec3& semiAxesMm, unsigned seed, int blobs)
    : centre_(centreMm), semi_(semiAxesMm) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> sigma(2.0, 5.0);
  for (int b = 0; b < blobs; ++b) {
    Vec3 c;
    for (int i = 0; i < 3; ++i) c[i] = centre_[i] + 0.8 * semi_[i] * unit(rng);
    blobs_.push_back({c, sigma(rng), (b % 2 ? 1.0 : -0.6) * (300.0 + 300.0 * std::abs(unit(rng)))});
  }
}

double BonePhantom::valueAt(const Vec3& p) const {
  // Normalised ellipsoidal radius; smooth edges (logistic, scale 1 mm, like a CT's blur) keep the
  // image band-limited, so linear interpolation of a 1-1.5 mm grid follows it closely.
  double r2 = 0.0;
  for (int i = 0; i < 3; ++i) r2 += (p[i] - centre_[i]) * (p[i] - centre_[i]) / (semi_[i] * semi_[i]);
  const double r = std::sqrt(r2);
  const double meanSemi = (semi_[0] + semi_[1] + semi_[2]) / 3.0;
  const double distMm = (r - 1.0) * meanSemi; // ~signed distance to the outer surface
  auto step = [](double x) { return 1.0 / (1.0 + std::exp(-x / 1.0)); };
  const double inside = step(-distMm);
  const double shell = step(distMm + 3.0) * inside; // 3 mm cortical shell
  double texture = 0.0;
  for (const Blob& b : blobs_) {
    double d2 = 0.0;
    for (int i = 0; i < 3; ++i) d2 += (p[i] - b.centre[i]) * (p[i] - b.centre[i]);
    if (d2 < 16.0 * b.sigma * b.sigma) texture += b.amplitude * std::exp(-0.5 * d2 / (b.sigma * b.sigma));
  }
  texture = std::clamp(texture, -400.0, 400.0);
  const double tissue = 0.0 + texture;
  return -1000.0 + inside * (1000.0 + tissue) + shell * (1200.0 - tissue);
}

Vec3 Affine::apply(const Vec3& x) const {
  Vec3 y;
  for (int r = 0; r < 3; ++r) {
    y[r] = centre[r] + translation[r];
    for (int c = 0; c < 3; ++c) y[r] += matrix[3 * r + c] * (x[c] - centre[c]);
  }
  return y;
}

Affine Affine::inverse() const {
  const auto& m = matrix;
  const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                     m[2] * (m[3] * m[7] - m[4] * m[6]);
  Affine inv;
  inv.matrix = {(m[4] * m[8] - m[5] * m[7]) / det, (m[2] * m[7] - m[1] * m[8]) / det,
                (m[1] * m[5] - m[2] * m[4]) / det, (m[5] * m[6] - m[3] * m[8]) / det,
                (m[0] * m[8] - m[2] * m[6]) / det, (m[2] * m[3] - m[0] * m[5]) / det,
                (m[3] * m[7] - m[4] * m[6]) / det, (m[1] * m[6] - m[0] * m[7]) / det,
                (m[0] * m[4] - m[1] * m[3]) / det};
  // x = M^-1 (y - c - t) + c: centre c + t, translation -t.
  for (int i = 0; i < 3; ++i) {
    inv.centre[i] = centre[i] + translation[i];
    inv.translation[i] = -translation[i];
  }
  return inv;
}

Affine Affine::fromParameters(const Vec3& rotDeg, const Vec3& scale, const Vec3& t, const Vec3& c) {
  const double k = M_PI / 180.0;
  const double a = rotDeg[0] * k, b = rotDeg[1] * k, g = rotDeg[2] * k;
  const double rx[9] = {1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a)};
  const double ry[9] = {std::cos(b), 0, std::sin(b), 0, 1, 0, -std::sin(b), 0, std::cos(b)};
  const double rz[9] = {std::cos(g), -std::sin(g), 0, std::sin(g), std::cos(g), 0, 0, 0, 1};
  auto mul = [](const double* p, const double* q, double* out) {
    for (int r = 0; r < 3; ++r)
      for (int cc = 0; cc < 3; ++cc) {
        out[3 * r + cc] = 0;
        for (int i = 0; i < 3; ++i) out[3 * r + cc] += p[3 * r + i] * q[3 * i + cc];
      }
  };
  double zy[9], rot[9];
  mul(rz, ry, zy);
  mul(zy, rx, rot);
  Affine A;
  for (int r = 0; r < 3; ++r)
    for (int cc = 0; cc < 3; ++cc) A.matrix[3 * r + cc] = rot[3 * r + cc] * scale[cc];
  A.centre = c;
  A.translation = t;
  return A;
}

ImageType::Pointer makeImage(const Grid& grid, float value) {
  auto image = ImageType::New();
  ImageType::RegionType region;
  ImageType::SpacingType spacing;
  ImageType::PointType origin;
  ImageType::DirectionType direction;
  for (unsigned i = 0; i < 3; ++i) {
    region.SetSize(i, grid.size[i]);
    spacing[i] = grid.spacing[i];
    origin[i] = grid.origin[i];
    for (unsigned j = 0; j < 3; ++j) direction[i][j] = grid.direction[3 * i + j];
  }
  image->SetRegions(region);
  image->SetSpacing(spacing);
  image->SetOrigin(origin);
  image->SetDirection(direction);
  image->Allocate();
  image->FillBuffer(value);
  return image;
}

namespace {
Vec3 physical(const Grid& g, double i, double j, double k) {
  const double u[3] = {i * g.spacing[0], j * g.spacing[1], k * g.spacing[2]};
  Vec3 p;
  for (int r = 0; r < 3; ++r)
    p[r] = g.origin[r] + g.direction[3 * r] * u[0] + g.direction[3 * r + 1] * u[1] +
           g.direction[3 * r + 2] * u[2];
  return p;
}
} // namespace

Vec3 gridCentre(const Grid& g) {
  return physical(g, (g.size[0] - 1) / 2.0, (g.size[1] - 1) / 2.0, (g.size[2] - 1) / 2.0);
}

ImageType::Pointer sample(const BonePhantom& phantom, const Grid& grid, const Affine& toImage,
                          const CementBall& cement) {
  auto image = makeImage(grid);
  const Affine back = toImage.inverse();
  float* out = image->GetBufferPointer();
  const long nz = grid.size[2];
#pragma omp parallel for schedule(static)
  for (long k = 0; k < nz; ++k) {
    std::size_t index = static_cast<std::size_t>(k) * grid.size[0] * grid.size[1];
    for (unsigned j = 0; j < grid.size[1]; ++j)
      for (unsigned i = 0; i < grid.size[0]; ++i, ++index) {
        const Vec3 y = physical(grid, i, j, static_cast<double>(k));
        double v = phantom.valueAt(back.apply(y));
        if (cement.radiusMm > 0.0) {
          double d2 = 0;
          for (int a = 0; a < 3; ++a) d2 += (y[a] - cement.centreMm[a]) * (y[a] - cement.centreMm[a]);
          // Smooth-edged ball (~0.5 mm ramp) so partial volume looks like a scanner's.
          const double w = 1.0 / (1.0 + std::exp((std::sqrt(d2) - cement.radiusMm) / 0.35));
          v = (1.0 - w) * v + w * cement.hu;
        }
        out[index] = static_cast<float>(v);
      }
  }
  return image;
}

double cornerTreMm(const Grid& grid, const Affine& truth,
                   const std::function<Vec3(const Vec3&)>& estimate) {
  double sum = 0.0;
  for (int c = 0; c < 8; ++c) {
    const Vec3 x = physical(grid, (c & 1) ? grid.size[0] - 1.0 : 0.0,
                            (c & 2) ? grid.size[1] - 1.0 : 0.0, (c & 4) ? grid.size[2] - 1.0 : 0.0);
    const Vec3 a = truth.apply(x);
    const Vec3 b = estimate(x);
    for (int i = 0; i < 3; ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  }
  return std::sqrt(sum / 8.0);
}

RegistrationCase makeRegistrationCase(unsigned n, double spacing, const Vec3& rot, const Vec3& scale,
                                      const Vec3& shift, bool cement,
                                      const std::array<double, 9>& direction, unsigned seed) {
  RegistrationCase c;
  c.grid.size = {n, n, n};
  c.grid.spacing = {spacing, spacing, spacing * 1.05};
  c.grid.direction = direction;
  c.grid.origin = {-40.0, 12.0, 100.0};
  const Vec3 centre = gridCentre(c.grid);
  const double half = 0.5 * (n - 1) * spacing;
  const BonePhantom phantom(centre, {0.78 * half, 0.66 * half, 0.72 * half}, seed);
  c.truth = Affine::fromParameters(rot, scale, shift, centre);
  c.fixed = sample(phantom, c.grid);
  CementBall ball;
  if (cement) {
    ball.centreMm = c.truth.apply({centre[0] + 0.2 * half, centre[1] - 0.15 * half, centre[2]});
    ball.radiusMm = 9.0;
  }
  c.moving = sample(phantom, c.grid, c.truth, ball);
  return c;
}

Vec3 writeCompareCase(const CompareCase& c, const std::string& directory) {
  const Vec3 centre = gridCentre(c.grid);
  const BonePhantom phantom(centre, c.semiAxesMm, c.seed);
  const Affine move = Affine::fromParameters(c.rotationDeg, c.scale, c.translationMm, centre);
  const Vec3 tip{centre[0] + 1.0, centre[1] - 1.0, centre[2]};
  const std::string dir = directory + "/";
  imaging::writeVolume(sample(phantom, c.grid), dir + "pre.nrrd");
  imaging::writeVolume(sample(phantom, c.grid, move, {move.apply(tip), c.cementRadiusMm, 3000.0}),
                       dir + "post.nrrd");
  imaging::writeVolume(
      sample(phantom, c.grid, {}, {{tip[0] + c.simOffsetMm, tip[1], tip[2]}, c.simRadiusMm, 2500.0}),
      dir + "sim.nrrd");
  return tip;
}

} // namespace cementsph::testing
