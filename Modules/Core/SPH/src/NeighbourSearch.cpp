#include "cementsph/sph/NeighbourSearch.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cementsph::sph {

void CellGrid::configure(const Domain& domain, double minCellSize) {
  if (!(minCellSize > 0.0)) throw std::invalid_argument("cell size must be positive");
  domain_ = domain;
  const Eigen::Vector3d extent = domain.extent();
  for (int a = 0; a < 3; ++a) {
    if (!(extent[a] > 0.0)) throw std::invalid_argument("simulation domain has zero extent");
    cellsPerAxis_[a] = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::floor(extent[a] / minCellSize)));
    inverseCellSize_[a] = static_cast<double>(cellsPerAxis_[a]) / extent[a];
  }
  const std::int64_t total = cellsPerAxis_[0] * cellsPerAxis_[1] * cellsPerAxis_[2];
  if (total > (std::int64_t{1} << 28)) throw std::invalid_argument("neighbour grid too large (over 2^28 cells)");

  // Precompute, per cell, its distinct neighbour cells. On a periodic axis with fewer than three
  // cells the offsets -1, 0, +1 wrap onto the same cell, hence the de-duplication.
  stencilOffset_.assign(static_cast<std::size_t>(total) + 1, 0);
  stencil_.clear();
  stencil_.reserve(static_cast<std::size_t>(total) * 27);
  const std::int64_t nx = cellsPerAxis_[0], ny = cellsPerAxis_[1], nz = cellsPerAxis_[2];
  for (std::int64_t k = 0; k < nz; ++k)
    for (std::int64_t j = 0; j < ny; ++j)
      for (std::int64_t i = 0; i < nx; ++i) {
        const std::size_t begin = stencil_.size();
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              std::int64_t c[3] = {i + di, j + dj, k + dk};
              bool inside = true;
              for (int a = 0; a < 3; ++a) {
                if (c[a] < 0 || c[a] >= cellsPerAxis_[a]) {
                  if (domain.periodic[a]) c[a] = (c[a] + cellsPerAxis_[a]) % cellsPerAxis_[a];
                  else inside = false;
                }
              }
              if (!inside) continue;
              const auto id = static_cast<std::uint32_t>(c[0] + nx * (c[1] + ny * c[2]));
              if (std::find(stencil_.begin() + static_cast<std::ptrdiff_t>(begin), stencil_.end(), id) == stencil_.end())
                stencil_.push_back(id);
            }
        // Sorted neighbour cells give a deterministic, memory-ordered traversal.
        std::sort(stencil_.begin() + static_cast<std::ptrdiff_t>(begin), stencil_.end());
        stencilOffset_[static_cast<std::size_t>(i + nx * (j + ny * k)) + 1] = static_cast<std::uint32_t>(stencil_.size());
      }
}

void CellGrid::cellCoordinates(double x, double y, double z, std::int64_t c[3]) const {
  const double p[3] = {x, y, z};
  for (int a = 0; a < 3; ++a) {
    std::int64_t v = static_cast<std::int64_t>(std::floor((p[a] - domain_.lower[a]) * inverseCellSize_[a]));
    c[a] = std::clamp<std::int64_t>(v, 0, cellsPerAxis_[a] - 1);
  }
}

int CellGrid::cellOf(double x, double y, double z) const {
  std::int64_t c[3];
  cellCoordinates(x, y, z, c);
  return cellIndex(c[0], c[1], c[2]);
}

void CellGrid::bin(const double* x, const double* y, const double* z, std::size_t n,
                   std::vector<std::uint32_t>& order, std::vector<std::uint32_t>& cellStart) const {
  const std::size_t cells = static_cast<std::size_t>(cellCount());
  std::vector<std::uint32_t> cellOfPoint(n);
  cellStart.assign(cells + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    cellOfPoint[i] = static_cast<std::uint32_t>(cellOf(x[i], y[i], z[i]));
    ++cellStart[cellOfPoint[i] + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) cellStart[c + 1] += cellStart[c];
  std::vector<std::uint32_t> cursor(cellStart.begin(), cellStart.end() - 1);
  order.resize(n);
  for (std::size_t i = 0; i < n; ++i) order[cursor[cellOfPoint[i]]++] = static_cast<std::uint32_t>(i);
}

} // namespace cementsph::sph
