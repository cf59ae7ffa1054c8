// Neighbour search made for this workload (Verlet lists over a uniform cell grid):
//  * a uniform grid whose cells are at least the kernel support plus the skin wide;
//  * fluid particles are reordered by cell at every rebuild, so neighbours sit close in memory;
//  * fixed particles are static: binned once, their grid is never rebuilt;
//  * per fluid particle, a compressed list of fluid and of fixed neighbours within support + skin,
//    reused until some particle has moved half the skin (skin = 0: rebuilt every step).
// Periodic axes use the minimum-image convention, so the box must be wider than twice the list radius.
#pragma once

#include "cementsph/sph/Domain.h"

#include <cstdint>
#include <vector>

namespace cementsph::sph {

class CellGrid {
public:
  // Cells at least `minCellSize` wide spanning the domain.
  void configure(const Domain& domain, double minCellSize);

  int cellCount() const { return static_cast<int>(cellsPerAxis_[0] * cellsPerAxis_[1] * cellsPerAxis_[2]); }
  const std::int64_t* cellsPerAxis() const { return cellsPerAxis_; }
  // Cell of a point; points outside an open axis are clamped to the border cell.
  int cellOf(double x, double y, double z) const;
  // The same as per-axis cell coordinates, and back.
  void cellCoordinates(double x, double y, double z, std::int64_t c[3]) const;
  int cellIndex(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return static_cast<int>(i + cellsPerAxis_[0] * (j + cellsPerAxis_[1] * k));
  }
  // The distinct cells within one cell of `cell` (<= 27; fewer at open borders or on narrow periodic axes).
  const std::uint32_t* neighbourCellsBegin(int cell) const { return &stencil_[stencilOffset_[cell]]; }
  const std::uint32_t* neighbourCellsEnd(int cell) const { return &stencil_[stencilOffset_[cell + 1]]; }

  // Counting sort of points by cell: `order` lists point indices cell by cell, `cellStart` has
  // cellCount()+1 offsets into it.
  void bin(const double* x, const double* y, const double* z, std::size_t n,
           std::vector<std::uint32_t>& order, std::vector<std::uint32_t>& cellStart) const;

private:
  Domain domain_;
  std::int64_t cellsPerAxis_[3] = {1, 1, 1};
  double inverseCellSize_[3] = {1, 1, 1};
  std::vector<std::uint32_t> stencilOffset_, stencil_;
};

// Compressed neighbour lists (CSR): the neighbours of particle i are index[offset[i] .. offset[i+1]).
struct NeighbourList {
  std::vector<std::uint64_t> offset;
  std::vector<std::uint32_t> index;
  std::size_t size() const { return index.size(); }
};

} // namespace cementsph::sph
