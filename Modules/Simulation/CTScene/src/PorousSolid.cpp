#include "cementsph/scene/PorousSolid.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace cementsph::scene {

namespace {
std::string mm(const Eigen::Vector3d& p) {
  std::ostringstream s;
  s << std::setprecision(6) << "(" << p.x() << ", " << p.y() << ", " << p.z() << ") mm";
  return s.str();
}
} // namespace

bool PorousSolid::voxelOf(const Eigen::Vector3d& p, std::array<int, 3>& ijk) const {
  for (int a = 0; a < 3; ++a) {
    const double u = (p[a] - grid.origin[a]) / grid.spacing[a];
    const long i = std::lround(u);
    if (!(u > -0.5) || i < 0 || i >= grid.size[a]) return false;
    ijk[a] = int(i);
  }
  return true;
}

PorousSolid buildPorousSolid(const imaging::ImageType* ct, const Eigen::Vector3d& tipMm, const PorousSolidOptions& o) {
  if (!ct) throw std::invalid_argument("CT: no image");
  if (!(o.roiSizeMm > 0) || !(o.reachMm > 0) || !(o.restDensity > 0) || !(o.massFactor > 0))
    throw std::invalid_argument("porous solid: roi size, reach, rest density and mass factor must be > 0");
  const auto& dir = ct->GetDirection();
  for (unsigned r = 0; r < 3; ++r)
    for (unsigned c = 0; c < 3; ++c)
      if (std::abs(dir[r][c] - (r == c ? 1.0 : 0.0)) > 1e-6)
        throw std::invalid_argument("CT: only an identity direction matrix is supported (resample the CT first)");
  const auto region = ct->GetLargestPossibleRegion();
  const auto start = region.GetIndex();
  const auto size = region.GetSize();
  Eigen::Vector3d origin, spacing; // mm, of voxel index 0 (not the region start)
  for (int a = 0; a < 3; ++a) {
    origin[a] = ct->GetOrigin()[a];
    spacing[a] = ct->GetSpacing()[a];
  }

  // Tip voxel (index relative to the region start); outside -> error.
  std::array<long, 3> tipIndex{};
  for (int a = 0; a < 3; ++a) {
    const double u = (tipMm[a] - origin[a]) / spacing[a] - double(start[a]);
    const long i = std::lround(u);
    if (!(u > -0.5) || i < 0 || i >= long(size[a])) {
      const Eigen::Vector3d lo = origin + spacing.cwiseProduct(Eigen::Vector3d(double(start[0]), double(start[1]), double(start[2]))) - 0.5 * spacing;
      const Eigen::Vector3d hi = lo + spacing.cwiseProduct(Eigen::Vector3d(double(size[0]), double(size[1]), double(size[2])));
      throw std::invalid_argument("tip " + mm(tipMm) + " lies outside the CT, which spans " + mm(lo) + " to " + mm(hi));
    }
    tipIndex[a] = i;
  }

  PorousSolid s;
  const double half = 0.5 * o.roiSizeMm;
  for (int a = 0; a < 3; ++a) {
    const double eps = 1e-9;
    long lo = long(std::ceil((tipMm[a] - half - origin[a]) / spacing[a] - eps)) - long(start[a]);
    long hi = long(std::floor((tipMm[a] + half - origin[a]) / spacing[a] + eps)) - long(start[a]);
    lo = std::clamp(lo, 0L, long(size[a]) - 1);
    hi = std::clamp(hi, 0L, long(size[a]) - 1);
    lo = std::min(lo, tipIndex[a]);
    hi = std::max(hi, tipIndex[a]);
    s.roiStart[a] = lo;
    s.roiSize[a] = hi - lo + 1;
    s.grid.size[a] = int(s.roiSize[a]);
    s.grid.spacing[a] = spacing[a] * 1e-3;
    s.grid.origin[a] = (origin[a] + spacing[a] * double(start[a] + lo)) * 1e-3;
  }
  s.lowerM = s.grid.origin - 0.5 * s.grid.spacing;
  s.upperM = s.grid.origin + s.grid.spacing.cwiseProduct(
                                 Eigen::Vector3d(s.grid.size[0] - 0.5, s.grid.size[1] - 0.5, s.grid.size[2] - 0.5));
  const int nx = s.grid.size[0], ny = s.grid.size[1], nz = s.grid.size[2];
  // Threshold, a row at a time straight from the buffer (GetPixel per voxel cost a whole-scan region a
  // large share of the run): ITK stores x fastest, so a row of the region is contiguous.
  s.solid.assign(s.grid.count(), 0);
  const auto* pixels = ct->GetBufferPointer();
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j) {
      imaging::ImageType::IndexType idx;
      idx[0] = start[0] + s.roiStart[0];
      idx[1] = start[1] + s.roiStart[1] + j;
      idx[2] = start[2] + s.roiStart[2] + k;
      const auto* row = pixels + ct->ComputeOffset(idx);
      std::uint8_t* out = &s.solid[s.grid.index(0, j, k)];
      for (int i = 0; i < nx; ++i)
        if (double(row[i]) > o.thresholdHu) {
          out[i] = 1;
          ++s.solidVoxels;
        }
    }

  const int ti = int(tipIndex[0] - s.roiStart[0]), tj = int(tipIndex[1] - s.roiStart[1]),
            tk = int(tipIndex[2] - s.roiStart[2]);
  if (s.solid[s.grid.index(ti, tj, tk)]) {
    imaging::ImageType::IndexType idx;
    for (int a = 0; a < 3; ++a) idx[unsigned(a)] = start[a] + tipIndex[a];
    std::ostringstream m;
    m << "tip " << mm(tipMm) << " lies in solid: its voxel has " << ct->GetPixel(idx) << " HU > threshold "
      << o.thresholdHu << " HU (move the tip into pore space)";
    throw std::invalid_argument(m.str());
  }

  // Pore space 6-connected to the tip within the ROI (flat indices: the grid is x fastest), by a span fill: each
  // run of pore voxels along x is taken whole and seeds the runs it touches in the four rows beside it (y +- 1,
  // z +- 1). The same set as a voxel-by-voxel breadth-first search, with streaming access along x and one seed a
  // run instead of a queue entry a voxel (issue 23: the search was the largest region-sized pass of a whole-scan
  // region, 186 of the 941 samples it adds over the 40 mm region at 5 ml).
  {
    std::vector<std::uint8_t> seen(s.grid.count(), 0);
    const std::size_t sx = std::size_t(nx), sy = std::size_t(ny), rowStride = sx, planeStride = sx * sy;
    std::vector<std::size_t> seeds{s.grid.index(ti, tj, tk)};
    auto open = [&](std::size_t m) { return !s.solid[m] && !seen[m]; };
    while (!seeds.empty()) {
      const std::size_t n = seeds.back();
      seeds.pop_back();
      if (seen[n]) continue; // filled from another seed since (a seed is pore by construction)
      const std::size_t row = n / sx, rowStart = row * sx, rowEnd = rowStart + sx; // [rowStart, rowEnd)
      std::size_t lo = n, hi = n + 1;                                                    // the run [lo, hi)
      while (lo > rowStart && open(lo - 1)) --lo;
      while (hi < rowEnd && open(hi)) ++hi;
      std::fill(seen.begin() + std::ptrdiff_t(lo), seen.begin() + std::ptrdiff_t(hi), std::uint8_t(1));
      s.connectedPoreVoxels += hi - lo;
      const std::size_t j = row % sy, k = row / sy;
      auto seedRow = [&](std::size_t offset, bool down) {
        bool inRun = false;
        for (std::size_t m = lo; m < hi; ++m) {
          const std::size_t q = down ? m - offset : m + offset;
          const bool pore = open(q);
          if (pore && !inRun) seeds.push_back(q);
          inRun = pore;
        }
      };
      if (j > 0) seedRow(rowStride, true);
      if (j + 1 < sy) seedRow(rowStride, false);
      if (k > 0) seedRow(planeStride, true);
      if (k + 1 < std::size_t(nz)) seedRow(planeStride, false);
    }
  }
  const double voxelMm3 = spacing.prod();
  if (double(s.connectedPoreVoxels) * voxelMm3 < o.requiredPoreVolumeMm3) {
    std::ostringstream m;
    m << "no pore space near the tip " << mm(tipMm) << ": the pores connected to it within the "
      << o.roiSizeMm << " mm region hold " << double(s.connectedPoreVoxels) * voxelMm3 * 1e-3 << " ml, less than the "
      << o.requiredPoreVolumeMm3 * 1e-3 << " ml to inject (volume_ml, --volume-ml): inject less or move the tip";
    throw std::invalid_argument(m.str());
  }

  s.spacingMm = spacing;
  s.particleMass = o.massFactor * o.restDensity * s.grid.voxelVolume();
  if (o.keptPositions) keepSolidNearPores(s, o.reachMm);
  return s;
}

void keepSolidNearPores(PorousSolid& s, double reachMm) {
  const Eigen::Vector3d& spacing = s.spacingMm;
  const int nx = s.grid.size[0], ny = s.grid.size[1], nz = s.grid.size[2];
  // Kept solid: a pore voxel at offset (a, b, c), |a| <= ri, |b| <= rj, |c| <= rk, with
  // d2 = (a sx)^2 + (b sy)^2 + (c sz)^2 <= reach^2 (1 + 1e-12). Separably, one axis at a time (each solid
  // voxel scanning every offset within reach cost the whole-scan region O(N r^3)): per row the nearest pore
  // along x, then per plane the least (a sx)^2 + (b sy)^2 over the rows within rj, then per solid voxel the
  // least of that plus (c sz)^2 over the planes within rk. The sums are formed in the same order,
  // ((a sx)^2 + (b sy)^2) + (c sz)^2, and rounding is monotone, so the least sum is exactly the least of the
  // per-offset sums: the same voxels are kept as by testing every offset.
  const int ri = int(std::floor(reachMm / spacing[0])), rj = int(std::floor(reachMm / spacing[1])),
            rk = int(std::floor(reachMm / spacing[2]));
  const double reach2 = reachMm * reachMm * (1 + 1e-12);
  auto squares = [](int r, double h) {
    std::vector<double> q(std::size_t(r) + 1);
    for (int a = 0; a <= r; ++a) q[std::size_t(a)] = std::pow(a * h, 2);
    return q;
  };
  const std::vector<double> ax = squares(ri, spacing[0]), by = squares(rj, spacing[1]), cz = squares(rk, spacing[2]);
  const double none = std::numeric_limits<double>::infinity();
  const std::size_t plane = std::size_t(nx) * std::size_t(ny);
  // Per plane: the least (a sx)^2 + (b sy)^2 to a pore of that plane, for planes k - rk .. k + rk (a ring).
  const int ringSize = 2 * rk + 1;
  std::vector<double> ring(std::size_t(ringSize) * plane, none);
  std::vector<int> nearestX(plane); // per voxel of one plane: |a| of the nearest pore in its row within ri, or -1
  auto fillPlane = [&](int k) {
    const std::uint8_t* solidPlane = &s.solid[std::size_t(k) * plane];
    for (int j = 0; j < ny; ++j) {
      const std::uint8_t* row = solidPlane + std::size_t(j) * std::size_t(nx);
      int* near = &nearestX[std::size_t(j) * std::size_t(nx)];
      long last = -(long(ri) + 1) - 1;
      for (int i = 0; i < nx; ++i) {
        if (!row[i]) last = i;
        near[i] = i - last <= ri ? int(i - last) : -1;
      }
      last = long(nx) + long(ri) + 1;
      for (int i = nx - 1; i >= 0; --i) {
        if (!row[i]) last = i;
        if (last - i <= ri && (near[i] < 0 || last - i < near[i])) near[i] = int(last - i);
      }
    }
    double* g = &ring[std::size_t(k % ringSize) * plane];
#pragma omp parallel for schedule(static)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        double best = 0.0; // a pore voxel: its own a = b = 0
        if (solidPlane[std::size_t(j) * std::size_t(nx) + std::size_t(i)]) {
          best = none;
          for (int b = std::max(-rj, -j); b <= std::min(rj, ny - 1 - j); ++b) {
            const int a = nearestX[std::size_t(j + b) * std::size_t(nx) + std::size_t(i)];
            if (a >= 0) best = std::min(best, ax[std::size_t(a)] + by[std::size_t(std::abs(b))]);
          }
        }
        g[std::size_t(j) * std::size_t(nx) + std::size_t(i)] = best;
      }
  };
  std::vector<std::uint8_t> keep(s.grid.count(), 0);
  std::size_t kept = 0;
  for (int m = 0; m < std::min(rk, nz); ++m) fillPlane(m);
  for (int k = 0; k < nz; ++k) {
    if (k + rk < nz) fillPlane(k + rk);
    const int c0 = std::max(-rk, -k), c1 = std::min(rk, nz - 1 - k);
#pragma omp parallel for schedule(static) reduction(+ : kept)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::size_t inPlane = std::size_t(j) * std::size_t(nx) + std::size_t(i);
        const std::size_t n = std::size_t(k) * plane + inPlane;
        if (!s.solid[n]) continue;
        // Nearest planes first: most kept voxels have their pore in their own plane.
        for (int d = 0; d <= rk; ++d)
          if ((-d >= c0 && ring[std::size_t((k - d) % ringSize) * plane + inPlane] + cz[std::size_t(d)] <= reach2) ||
              (d > 0 && d <= c1 && ring[std::size_t((k + d) % ringSize) * plane + inPlane] + cz[std::size_t(d)] <= reach2)) {
            keep[n] = 1;
            ++kept;
            break;
          }
      }
  }
  s.positions.clear();
  s.positions.reserve(kept);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        if (keep[s.grid.index(i, j, k)]) s.positions.push_back(s.grid.centre(i, j, k));
  s.keptVoxels = s.positions.size();
}

} // namespace cementsph::scene
