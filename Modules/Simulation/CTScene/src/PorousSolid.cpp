#include "cementsph/scene/PorousSolid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace cementsph::scene {

namespace {
#if defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
constexpr bool kLittleEndian = true;
#else
constexpr bool kLittleEndian = false;
#endif
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
  // large share of the run): ITK stores x fastest, so a row of the region is contiguous. Branch-free (a foam's
  // solid and pore voxels alternate at random: a branch per voxel mispredicts half the time), and each row's
  // pore voxels also go into a bit row for the connected-pore search below.
  const std::size_t words = (std::size_t(nx) + 63) / 64, rows = std::size_t(ny) * std::size_t(nz);
  std::vector<std::uint64_t> open(rows * words, 0); // a bit per pore voxel not yet reached; x fastest, rows padded
  s.solid.resize(s.grid.count());
  const auto* pixels = ct->GetBufferPointer();
  // float(v) > t (a double) exactly when v > tf, tf the largest float <= t: a float comparison, which vectorises.
  float tf = float(o.thresholdHu);
  if (double(tf) > o.thresholdHu) tf = std::nextafter(tf, -std::numeric_limits<float>::infinity());
  std::size_t poreVoxels = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j) {
      imaging::ImageType::IndexType idx;
      idx[0] = start[0] + s.roiStart[0];
      idx[1] = start[1] + s.roiStart[1] + j;
      idx[2] = start[2] + s.roiStart[2] + k;
      const auto* row = pixels + ct->ComputeOffset(idx);
      std::uint8_t* out = &s.solid[s.grid.index(0, j, k)];
      for (int i = 0; i < nx; ++i) out[i] = row[i] > tf;
      // Eight 0/1 bytes at a time to eight bits: the multiply gathers byte b's low bit into bit 56 + b (byte b
      // the b-th lowest: little-endian; elsewhere a bit at a time).
      std::uint64_t* bits = &open[(std::size_t(j) + std::size_t(ny) * std::size_t(k)) * words];
      const std::size_t whole = kLittleEndian ? std::size_t(nx) / 8 : 0;
      for (std::size_t g = 0; g < whole; ++g) {
        std::uint64_t bytes;
        std::memcpy(&bytes, out + 8 * g, 8);
        const std::uint64_t pore = ((bytes ^ 0x0101010101010101ULL) * 0x0102040810204080ULL) >> 56;
        bits[g / 8] |= pore << (8 * (g % 8));
      }
      for (std::size_t i = 8 * whole; i < std::size_t(nx); ++i) bits[i / 64] |= std::uint64_t(out[i] == 0) << (i % 64);
      for (std::size_t w = 0; w < words; ++w) poreVoxels += std::size_t(__builtin_popcountll(bits[w]));
    }
  s.solidVoxels = s.grid.count() - poreVoxels;

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

  // Pore space 6-connected to the tip within the ROI, by a span fill on the bit rows: each run of pore voxels
  // along x is taken whole (its bits cleared: reached) and seeds the runs it touches in the four rows beside it
  // (y +- 1, z +- 1), 64 voxels a word. The same set as a voxel-by-voxel breadth-first search (the test
  // compares them on random media); issue 23: the search was the largest region-sized pass of a whole-scan
  // region, and a byte per voxel (a branch per voxel on a foam) cost it 0.1 s on a 200 x 200 x 188 CT.
  {
    const std::size_t sx = std::size_t(nx), sy = std::size_t(ny), sz = std::size_t(nz);
    auto maskIn = [](std::size_t w, std::size_t lo, std::size_t hi) -> std::uint64_t { // bits of word w in [lo, hi)
      const std::size_t a = std::max(lo, 64 * w), b = std::min(hi, 64 * w + 64);
      if (a >= b) return 0;
      const unsigned count = unsigned(b - a), shift = unsigned(a - 64 * w);
      return (count == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << count) - 1) << shift;
    };
    std::vector<std::pair<std::size_t, std::size_t>> seeds{{std::size_t(tj) + sy * std::size_t(tk), std::size_t(ti)}};
    while (!seeds.empty()) {
      const auto [row, x] = seeds.back();
      seeds.pop_back();
      std::uint64_t* r = &open[row * words];
      if (!((r[x >> 6] >> (x & 63)) & 1)) continue; // reached from another seed since
      // The run [lo, hi): hi the first bit at or after x that is not open (the padding bits never are), lo one
      // past the last one before x.
      std::size_t hi;
      {
        std::size_t w = x >> 6;
        std::uint64_t m = ~r[w] & (~std::uint64_t(0) << (x & 63));
        while (m == 0 && ++w < words) m = ~r[w];
        hi = w < words ? std::min(sx, 64 * w + std::size_t(__builtin_ctzll(m))) : sx;
      }
      std::size_t lo;
      {
        std::size_t w = x >> 6;
        const unsigned b = unsigned(x & 63);
        std::uint64_t m = b ? ~r[w] & ((std::uint64_t(1) << b) - 1) : 0;
        while (m == 0 && w > 0) m = ~r[--w];
        lo = m ? 64 * w + 64 - std::size_t(__builtin_clzll(m)) : 0;
      }
      const std::size_t w0 = lo >> 6, w1 = (hi - 1) >> 6;
      for (std::size_t w = w0; w <= w1; ++w) r[w] &= ~maskIn(w, lo, hi);
      s.connectedPoreVoxels += hi - lo;
      // Each run of open bits within [lo, hi) of a neighbouring row: one seed at its first bit.
      auto seedRow = [&](std::size_t q) {
        const std::uint64_t* n = &open[q * words];
        std::uint64_t carry = 0;
        for (std::size_t w = w0; w <= w1; ++w) {
          const std::uint64_t m = n[w] & maskIn(w, lo, hi);
          std::uint64_t starts = m & ~((m << 1) | carry);
          carry = m >> 63;
          while (starts) {
            seeds.emplace_back(q, 64 * w + std::size_t(__builtin_ctzll(starts)));
            starts &= starts - 1;
          }
        }
      };
      const std::size_t j = row % sy, k = row / sy;
      if (j > 0) seedRow(row - 1);
      if (j + 1 < sy) seedRow(row + 1);
      if (k > 0) seedRow(row - sy);
      if (k + 1 < sz) seedRow(row + sy);
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
