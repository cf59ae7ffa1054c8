#include "cementsph/sph/FixedParticleField.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cementsph::sph {

void FixedParticleField::configure(const Domain& domain, double nodeSpacing, double smoothingLength) {
  if (!(nodeSpacing > 0) || !(smoothingLength > 0)) throw std::invalid_argument("fixed field: spacing and h must be positive");
  for (int a = 0; a < 3; ++a)
    if (domain.periodic[a]) throw std::invalid_argument("fixed field: periodic sides are not supported (use exact sums)");
  domain_ = domain;
  nodeSpacing_ = nodeSpacing;
  inverseSpacing_ = 1.0 / nodeSpacing;
  h_ = smoothingLength;
  const Eigen::Vector3d e = domain.extent();
  std::size_t total = 1;
  for (int a = 0; a < 3; ++a) {
    const auto cells = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(e[a] * inverseSpacing_)));
    bricksPerAxis_[a] = (cells + kBrick - 1) / kBrick;
    total *= static_cast<std::size_t>(bricksPerAxis_[a]);
  }
  bricks_.clear();
  bricks_.resize(total);
  filled_ = 0;
}

void FixedParticleField::attach(const FixedParticles* fixed, const CellGrid* grid,
                                const std::vector<std::uint32_t>* cellStart) {
  fixed_ = fixed;
  grid_ = grid;
  cellStart_ = cellStart;
  for (auto& b : bricks_) b.reset();
  filled_ = 0;
}

std::size_t FixedParticleField::brickIndex(double x, double y, double z, int local[3], double frac[3]) const {
  const double p[3] = {x, y, z};
  std::int64_t b[3];
  for (int a = 0; a < 3; ++a) {
    const double u = (p[a] - domain_.lower[a]) * inverseSpacing_;
    const std::int64_t cells = bricksPerAxis_[a] * kBrick;
    const std::int64_t c = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(u)), 0, cells - 1);
    frac[a] = std::clamp(u - static_cast<double>(c), 0.0, 1.0);
    b[a] = c / kBrick;
    local[a] = static_cast<int>(c - b[a] * kBrick);
  }
  return static_cast<std::size_t>((b[2] * bricksPerAxis_[1] + b[1]) * bricksPerAxis_[0] + b[0]);
}

void FixedParticleField::fillBrick(std::size_t b) {
  // Scatter: each fixed particle within reach of the brick adds to the nodes inside its support (about
  // half of its bounding cube), rather than each node searching ~10x more candidates than it keeps.
  // The nodes then hold the exact sums (tested against a brute-force sum).
  const std::int64_t bx = static_cast<std::int64_t>(b) % bricksPerAxis_[0];
  const std::int64_t by = (static_cast<std::int64_t>(b) / bricksPerAxis_[0]) % bricksPerAxis_[1];
  const std::int64_t bz = static_cast<std::int64_t>(b) / (bricksPerAxis_[0] * bricksPerAxis_[1]);
  FixedSums* nodes = bricks_[b].get();
  std::fill(nodes, nodes + kNodesPerBrick, FixedSums{});
  if (!fixed_ || fixed_->size() == 0 || cellStart_->empty()) return;
  const double origin[3] = {domain_.lower.x() + static_cast<double>(bx * kBrick) * nodeSpacing_,
                            domain_.lower.y() + static_cast<double>(by * kBrick) * nodeSpacing_,
                            domain_.lower.z() + static_cast<double>(bz * kBrick) * nodeSpacing_};
  const double reach = 2.0 * h_, reach2 = reach * reach, edge = kBrick * nodeSpacing_;
  const CubicSplineKernel cubic(h_);
  const SpikyKernel spiky(h_);
  std::int64_t c0[3], c1[3];
  grid_->cellCoordinates(origin[0] - reach, origin[1] - reach, origin[2] - reach, c0);
  grid_->cellCoordinates(origin[0] + edge + reach, origin[1] + edge + reach, origin[2] + edge + reach, c1);
  const std::vector<std::uint32_t>& start = *cellStart_;
  auto nodeRange = [&](double p, int a, double halfWidth, int& lo, int& hi) {
    lo = std::max(0, static_cast<int>(std::ceil((p - halfWidth - origin[a]) * inverseSpacing_)));
    hi = std::min(kBrick, static_cast<int>(std::floor((p + halfWidth - origin[a]) * inverseSpacing_)));
  };
  for (std::int64_t ck = c0[2]; ck <= c1[2]; ++ck)
    for (std::int64_t cj = c0[1]; cj <= c1[1]; ++cj)
      for (std::int64_t ci = c0[0]; ci <= c1[0]; ++ci) {
        const int cell = grid_->cellIndex(ci, cj, ck);
        for (std::uint32_t p = start[static_cast<std::size_t>(cell)]; p < start[static_cast<std::size_t>(cell) + 1]; ++p) {
          const double px = fixed_->x[p], py = fixed_->y[p], pz = fixed_->z[p];
          const double m = static_cast<double>(byVolume_ ? fixed_->volume[p] : fixed_->mass[p]);
          int k0, k1;
          nodeRange(pz, 2, reach, k0, k1);
          for (int k = k0; k <= k1; ++k) {
            const double dz = origin[2] + k * nodeSpacing_ - pz;
            const double restZ = reach2 - dz * dz;
            if (restZ <= 0) continue;
            int j0, j1;
            nodeRange(py, 1, std::sqrt(restZ), j0, j1);
            for (int j = j0; j <= j1; ++j) {
              const double dy = origin[1] + j * nodeSpacing_ - py;
              const double restY = restZ - dy * dy;
              if (restY <= 0) continue;
              int i0, i1;
              nodeRange(px, 0, std::sqrt(restY), i0, i1);
              FixedSums* row = nodes + (k * kNodesPerEdge + j) * kNodesPerEdge;
              for (int i = i0; i <= i1; ++i) {
                const double dx = origin[0] + i * nodeSpacing_ - px;
                const double r2 = dx * dx + dy * dy + dz * dz;
                if (r2 >= reach2) continue;
                const double r = std::sqrt(r2);
                row[i].density += m * cubic.value(r);
                if (r > 1e-12 * h_) {
                  const double g = m * spiky.derivative(r) / r;
                  row[i].gradient[0] += g * dx; row[i].gradient[1] += g * dy; row[i].gradient[2] += g * dz;
                }
              }
            }
          }
        }
      }
}

void FixedParticleField::prepare(const double* x, const double* y, const double* z, std::size_t n) {
  if (!configured()) throw std::logic_error("fixed field used before configure()");
  std::vector<std::size_t> todo;
  int local[3];
  double frac[3];
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t b = brickIndex(x[i], y[i], z[i], local, frac);
    if (!bricks_[b]) {
      bricks_[b] = std::make_unique<FixedSums[]>(kNodesPerBrick);
      todo.push_back(b);
    }
  }
  if (todo.empty()) return;
  const std::ptrdiff_t count = static_cast<std::ptrdiff_t>(todo.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (std::ptrdiff_t t = 0; t < count; ++t) fillBrick(todo[static_cast<std::size_t>(t)]);
  filled_ += todo.size();
}

void FixedParticleField::sample(double x, double y, double z, double& density, double gradient[3]) const {
  int l[3];
  double f[3];
  const FixedSums* nodes = bricks_[brickIndex(x, y, z, l, f)].get();
  if (!nodes) throw std::logic_error("fixed field sampled outside its prepared bricks (call prepare first)");
  const double g[3] = {1.0 - f[0], 1.0 - f[1], 1.0 - f[2]};
  double d = 0.0, gx = 0.0, gy = 0.0, gz = 0.0;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const FixedSums& s = nodes[((l[2] + k) * kNodesPerEdge + (l[1] + j)) * kNodesPerEdge + (l[0] + i)];
        const double w = (i ? f[0] : g[0]) * (j ? f[1] : g[1]) * (k ? f[2] : g[2]);
        d += w * s.density;
        gx += w * s.gradient[0]; gy += w * s.gradient[1]; gz += w * s.gradient[2];
      }
  density = d;
  gradient[0] = gx; gradient[1] = gy; gradient[2] = gz;
}

} // namespace cementsph::sph
