#include "cementsph/sph/ParticleVoxeliser.h"

#include "cementsph/sph/Kernels.h"
#include "cementsph/sph/Particles.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace cementsph::sph {

ParticleVoxeliser::ParticleVoxeliser(const VoxelGrid& grid, double smoothingLength) : grid_(grid), h_(smoothingLength) {
  for (int a = 0; a < 3; ++a) {
    if (!(std::isfinite(grid.spacing[a]) && grid.spacing[a] > 0))
      throw std::invalid_argument("voxeliser: voxel spacing must be positive on every axis");
    if (grid.size[a] < 1) throw std::invalid_argument("voxeliser: the grid needs at least one voxel per axis");
  }
  if (!grid.origin.allFinite()) throw std::invalid_argument("voxeliser: grid origin is not finite");
  if (!(std::isfinite(smoothingLength) && smoothingLength > 0))
    throw std::invalid_argument("voxeliser: smoothing length h must be positive");
}

std::vector<double> ParticleVoxeliser::density(const FluidParticles& fluid) const {
  return density(fluid.x.data(), fluid.y.data(), fluid.z.data(), fluid.mass.data(), fluid.size());
}

std::vector<double> ParticleVoxeliser::density(const double* x, const double* y, const double* z, const double* mass,
                                               std::size_t n) const {
  std::vector<double> rho(grid_.count(), 0.0);
  if (n == 0) return rho;
  const CubicSplineKernel W(h_);
  const double support = W.support(), support2 = support * support;

  // Cells of width 2h over the grid's extent widened by the support; particles outside cannot reach a voxel.
  const Eigen::Vector3d lo = grid_.origin - Eigen::Vector3d::Constant(support);
  Eigen::Vector3d hi = grid_.origin + Eigen::Vector3d::Constant(support);
  for (int a = 0; a < 3; ++a) hi[a] += grid_.spacing[a] * (grid_.size[a] - 1);
  std::int64_t nc[3];
  for (int a = 0; a < 3; ++a) nc[a] = std::max<std::int64_t>(1, std::int64_t(std::ceil((hi[a] - lo[a]) / support)));
  const std::size_t cells = std::size_t(nc[0] * nc[1] * nc[2]);
  auto cellCoord = [&](double p, int a) { return std::int64_t(std::floor((p - lo[a]) / support)); };

  // Counting sort of the particles that can reach the grid.
  std::vector<std::uint32_t> start(cells + 1, 0);
  std::vector<std::int64_t> cellOf(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t c[3] = {cellCoord(x[i], 0), cellCoord(y[i], 1), cellCoord(z[i], 2)};
    bool inside = true;
    for (int a = 0; a < 3; ++a) inside = inside && c[a] >= 0 && c[a] < nc[a];
    if (!inside) continue;
    cellOf[i] = c[0] + nc[0] * (c[1] + nc[1] * c[2]);
    ++start[std::size_t(cellOf[i]) + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  std::vector<std::uint32_t> cursor(start.begin(), start.end() - 1), order(start[cells]);
  for (std::size_t i = 0; i < n; ++i)
    if (cellOf[i] >= 0) order[cursor[std::size_t(cellOf[i])]++] = std::uint32_t(i);

  const int nx = grid_.size[0], ny = grid_.size[1], nz = grid_.size[2];
  const std::int64_t planes = std::int64_t(ny) * nz;
#pragma omp parallel for schedule(dynamic, 4)
  for (std::int64_t jk = 0; jk < planes; ++jk) { // one row of voxels along x per iteration
    const int j = int(jk % ny), k = int(jk / ny);
    for (int i = 0; i < nx; ++i) {
      const Eigen::Vector3d v = grid_.centre(i, j, k);
      const std::int64_t c[3] = {cellCoord(v.x(), 0), cellCoord(v.y(), 1), cellCoord(v.z(), 2)};
      double sum = 0;
      for (std::int64_t ck = std::max<std::int64_t>(0, c[2] - 1); ck <= std::min(nc[2] - 1, c[2] + 1); ++ck)
        for (std::int64_t cj = std::max<std::int64_t>(0, c[1] - 1); cj <= std::min(nc[1] - 1, c[1] + 1); ++cj)
          for (std::int64_t ci = std::max<std::int64_t>(0, c[0] - 1); ci <= std::min(nc[0] - 1, c[0] + 1); ++ci) {
            const std::size_t cell = std::size_t(ci + nc[0] * (cj + nc[1] * ck));
            for (std::uint32_t q = start[cell]; q < start[cell + 1]; ++q) {
              const std::uint32_t p = order[q];
              const double dx = v.x() - x[p], dy = v.y() - y[p], dz = v.z() - z[p];
              const double r2 = dx * dx + dy * dy + dz * dz;
              if (r2 < support2) sum += mass[p] * W.value(std::sqrt(r2)); // Eq. 2
            }
          }
      rho[grid_.index(i, j, k)] = sum;
    }
  }
  return rho;
}

double ParticleVoxeliser::integratedMass(const std::vector<double>& density) const {
  double sum = 0;
  for (double r : density) sum += r;
  return sum * grid_.voxelVolume();
}

} // namespace cementsph::sph
