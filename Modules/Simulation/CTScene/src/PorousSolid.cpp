#include "cementsph/scene/PorousSolid.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <iomanip>
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
  s.solid.assign(s.grid.count(), 0);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        imaging::ImageType::IndexType idx;
        idx[0] = start[0] + s.roiStart[0] + i;
        idx[1] = start[1] + s.roiStart[1] + j;
        idx[2] = start[2] + s.roiStart[2] + k;
        if (double(ct->GetPixel(idx)) > o.thresholdHu) {
          s.solid[s.grid.index(i, j, k)] = 1;
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

  // Pore space 6-connected to the tip within the ROI.
  {
    std::vector<std::uint8_t> seen(s.grid.count(), 0);
    std::deque<std::array<int, 3>> queue{{ti, tj, tk}};
    seen[s.grid.index(ti, tj, tk)] = 1;
    const int steps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    while (!queue.empty()) {
      const auto v = queue.front();
      queue.pop_front();
      ++s.connectedPoreVoxels;
      for (const auto& st : steps) {
        const int a = v[0] + st[0], b = v[1] + st[1], c = v[2] + st[2];
        if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
        const std::size_t n = s.grid.index(a, b, c);
        if (seen[n] || s.solid[n]) continue;
        seen[n] = 1;
        queue.push_back({a, b, c});
      }
    }
  }
  const double voxelMm3 = spacing.prod();
  if (double(s.connectedPoreVoxels) * voxelMm3 < o.requiredPoreVolumeMm3) {
    std::ostringstream m;
    m << "no pore space near the tip " << mm(tipMm) << ": the pores connected to it within the "
      << o.roiSizeMm << " mm region hold " << double(s.connectedPoreVoxels) * voxelMm3 * 1e-3 << " ml, less than the "
      << o.requiredPoreVolumeMm3 * 1e-3 << " ml to inject";
    throw std::invalid_argument(m.str());
  }

  // Offsets within reach, nearest first (most solid surface voxels find a pore at once).
  std::vector<std::pair<double, std::array<int, 3>>> byDistance;
  const int ri = int(std::floor(o.reachMm / spacing[0])), rj = int(std::floor(o.reachMm / spacing[1])),
            rk = int(std::floor(o.reachMm / spacing[2]));
  for (int c = -rk; c <= rk; ++c)
    for (int b = -rj; b <= rj; ++b)
      for (int a = -ri; a <= ri; ++a) {
        const double d2 = std::pow(a * spacing[0], 2) + std::pow(b * spacing[1], 2) + std::pow(c * spacing[2], 2);
        if ((a || b || c) && d2 <= o.reachMm * o.reachMm * (1 + 1e-12)) byDistance.push_back({d2, {a, b, c}});
      }
  std::sort(byDistance.begin(), byDistance.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<std::uint8_t> keep(s.grid.count(), 0);
#pragma omp parallel for schedule(dynamic)
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::size_t n = s.grid.index(i, j, k);
        if (!s.solid[n]) continue;
        for (const auto& [d2, off] : byDistance) {
          const int a = i + off[0], b = j + off[1], c = k + off[2];
          if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
          if (!s.solid[s.grid.index(a, b, c)]) {
            keep[n] = 1;
            break;
          }
        }
      }
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        if (keep[s.grid.index(i, j, k)]) s.positions.push_back(s.grid.centre(i, j, k));
  s.keptVoxels = s.positions.size();
  s.particleMass = o.massFactor * o.restDensity * s.grid.voxelVolume();
  return s;
}

} // namespace cementsph::scene
