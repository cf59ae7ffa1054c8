#include "cementsph/scene/InputGridPaste.h"

#include "cementsph/imaging/AffineRegistration.h"
#include "cementsph/scene/AxisAlignedCT.h"

#include <itkIdentityTransform.h>
#include <itkImageRegionIteratorWithIndex.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace cementsph::scene {

namespace {

void requireWhole(const imaging::ImageType* image, const char* what) {
  if (!image) throw std::invalid_argument(std::string("paste-back: no ") + what + " image");
  if (image->GetBufferedRegion() != image->GetLargestPossibleRegion())
    throw std::invalid_argument(std::string("paste-back: the ") + what + " image is only partly in memory");
}

// True when the direction matrix has exact zeros off its diagonal (an axial CT; its diagonal need not be
// exactly 1: a reader that normalises 0.47 mm space directions gets 1 - 1 ulp). Then ITK's index-to-point
// matrix is exactly diagonal, its per-voxel transform adds exact zeros for the other axes, and coordinate a
// of a voxel centre depends on index a alone, so one table per axis gives bit for bit what a transform per
// voxel gives. This is what lets a whole-scan region cost a few passes over memory instead of matrix
// products and roundings per voxel.
bool separable(const imaging::ImageType* image) {
  const auto& d = image->GetDirection();
  for (unsigned r = 0; r < 3; ++r)
    for (unsigned c = 0; c < 3; ++c)
      if (r != c && d[r][c] != 0.0) return false;
  return true;
}

// Coordinate a [mm] of the centre of each index start .. start + count - 1 along axis a, by ITK's own transform.
std::vector<double> centresAlong(const imaging::ImageType* image, unsigned a, long start, long count) {
  std::vector<double> x(std::size_t(std::max(count, 0L)));
  imaging::ImageType::IndexType index = image->GetLargestPossibleRegion().GetIndex();
  for (long i = 0; i < count; ++i) {
    index[a] = start + i;
    imaging::ImageType::PointType p;
    image->TransformIndexToPhysicalPoint(index, p);
    x[std::size_t(i)] = p[a];
  }
  return x;
}

// True when the per-axis tables of pasteOntoInputGrid say that input voxel i is simulated voxel i on every
// axis: the same count, every input centre inside the box and on the centre of the simulated voxel of its index.
bool voxelForVoxel(const std::array<long, 3>& lo, const std::array<long, 3>& hi, const std::array<long, 3>& inStart,
                   const std::array<long, 3>& inSize, const std::array<long, 3>& n,
                   const std::array<std::vector<std::uint8_t>, 3>& inside,
                   const std::array<std::vector<std::uint8_t>, 3>& centre, const std::array<std::vector<long>, 3>& near) {
  for (unsigned a = 0; a < 3; ++a) {
    if (lo[a] != inStart[a] || hi[a] != inStart[a] + inSize[a] - 1 || n[a] != inSize[a]) return false;
    for (std::size_t t = 0; t < near[a].size(); ++t)
      if (!inside[a][t] || !centre[a][t] || near[a][t] != long(t)) return false;
  }
  return true;
}

} // namespace

imaging::ImageType::Pointer alignedBackgroundOn(const imaging::ImageType* input, const imaging::ImageType* grid) {
  requireWhole(input, "input CT");
  if (!grid) throw std::invalid_argument("paste-back: no grid to sample the CT on");
  if (!isAxisAligned(grid)) throw std::invalid_argument("paste-back: the simulated CT's grid is not axis-aligned");
  if (!isAxisAligned(input) && !axisPermutation(input)) {
    // Oblique: the same trilinear sampling axisAligned() did, at these voxel centres only.
    auto identity = itk::IdentityTransform<double, 3>::New();
    return imaging::resampleOnto(input, grid, identity, kOutsideScanHu);
  }
  // Axial or reoriented: every centre of the aligned grid is an input voxel centre, so the input's voxel
  // (TransformPhysicalPointToIndex rounds to the nearest) is the value itself.
  auto out = imaging::ImageType::New();
  out->SetRegions(grid->GetLargestPossibleRegion());
  out->CopyInformation(grid);
  out->Allocate();
  if (isAxisAligned(input) && separable(input) && separable(grid)) {
    // Per axis, the input index of each grid centre, or -1 outside the input; then rows copied. The centres
    // coincide with input centres (the grid is a region of the aligned CT), so the continuous index is an
    // integer up to round-off and rounding it is what TransformPhysicalPointToIndex does; a grid that does
    // not coincide (to 1e-3 voxel) takes the general path below.
    const auto gridRegion = grid->GetLargestPossibleRegion(), inRegion = input->GetLargestPossibleRegion();
    std::array<std::vector<long>, 3> at;
    bool coincide = true;
    for (unsigned a = 0; a < 3 && coincide; ++a)
      for (const double x : centresAlong(grid, a, long(gridRegion.GetIndex()[a]), long(gridRegion.GetSize()[a]))) {
        const double c = (x - input->GetOrigin()[a]) / input->GetSpacing()[a];
        const double r = std::round(c);
        coincide = coincide && std::abs(c - r) <= 1e-3;
        const long i = long(r) - long(inRegion.GetIndex()[a]);
        at[a].push_back(i >= 0 && i < long(inRegion.GetSize()[a]) ? i : -1);
      }
    if (coincide) {
      const float* in = input->GetBufferPointer();
      float* dst = out->GetBufferPointer();
      const std::size_t nx = at[0].size(), ny = at[1].size(), nz = at[2].size();
      const std::size_t sx = inRegion.GetSize()[0], sy = inRegion.GetSize()[1];
      for (std::size_t k = 0; k < nz; ++k)
        for (std::size_t j = 0; j < ny; ++j) {
          float* row = dst + nx * (j + ny * k);
          if (at[1][j] < 0 || at[2][k] < 0) {
            std::fill(row, row + nx, kOutsideScanHu);
            continue;
          }
          const float* from = in + sx * (std::size_t(at[1][j]) + sy * std::size_t(at[2][k]));
          for (std::size_t i = 0; i < nx; ++i) row[i] = at[0][i] < 0 ? kOutsideScanHu : from[at[0][i]];
        }
      return out;
    }
  }
  itk::ImageRegionIteratorWithIndex<imaging::ImageType> it(out, out->GetLargestPossibleRegion());
  for (; !it.IsAtEnd(); ++it) {
    imaging::ImageType::PointType p;
    out->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    imaging::ImageType::IndexType index;
    it.Set(input->TransformPhysicalPointToIndex(p, index) ? input->GetPixel(index) : kOutsideScanHu);
  }
  return out;
}

imaging::ImageType::Pointer pasteOntoInputGrid(const imaging::ImageType* input, const imaging::ImageType* simulated,
                                               const imaging::ImageType* background) {
  requireWhole(input, "input CT");
  requireWhole(simulated, "simulated CT");
  requireWhole(background, "background");
  if (!isAxisAligned(simulated)) throw std::invalid_argument("paste-back: the simulated CT's grid is not axis-aligned");
  const auto simRegion = simulated->GetLargestPossibleRegion();
  bool sameGrid = background->GetLargestPossibleRegion() == simRegion && isAxisAligned(background);
  for (unsigned a = 0; a < 3 && sameGrid; ++a) {
    const double h = simulated->GetSpacing()[a];
    sameGrid = std::abs(background->GetSpacing()[a] - h) <= 1e-9 * h &&
               std::abs(background->GetOrigin()[a] - simulated->GetOrigin()[a]) <= 1e-6 * h;
  }
  if (!sameGrid) throw std::invalid_argument("paste-back: the background is not on the simulated CT's grid");

  auto out = imaging::ImageType::New();
  out->SetRegions(input->GetLargestPossibleRegion());
  out->CopyInformation(input);
  out->Allocate();
  const auto inRegion = input->GetLargestPossibleRegion();
  const std::size_t inCount = inRegion.GetNumberOfPixels();
  std::copy(input->GetBufferPointer(), input->GetBufferPointer() + inCount, out->GetBufferPointer());

  std::array<long, 3> n{};
  std::array<double, 3> o{}, h{}; // simulated voxel (region-relative) u lies at o + h u
  for (unsigned a = 0; a < 3; ++a) {
    n[a] = long(simRegion.GetSize()[a]);
    h[a] = simulated->GetSpacing()[a];
    o[a] = simulated->GetOrigin()[a] + h[a] * double(simRegion.GetIndex()[a]);
  }
  if (n[0] == 0 || n[1] == 0 || n[2] == 0) return out;
  const float* sim = simulated->GetBufferPointer();
  const float* bg = background->GetBufferPointer();
  const float* in = input->GetBufferPointer();
  float* dst = out->GetBufferPointer();
  auto simOffset = [&](long i, long j, long k) { return std::size_t(i + n[0] * (j + n[1] * k)); };
  const std::size_t simCount = std::size_t(n[0] * n[1] * n[2]);

  // The input indices the simulated box can reach: its 8 corners mapped into the input's index space,
  // widened to whole voxels and clipped to the input's region (so no index below can leave the buffer).
  std::array<double, 3> cLo, cHi;
  cLo.fill(std::numeric_limits<double>::infinity());
  cHi.fill(-std::numeric_limits<double>::infinity());
  for (int corner = 0; corner < 8; ++corner) {
    imaging::ImageType::PointType p;
    for (unsigned a = 0; a < 3; ++a) p[a] = o[a] + h[a] * (((corner >> a) & 1) ? double(n[a]) - 0.5 : -0.5);
    itk::ContinuousIndex<double, 3> c;
    input->TransformPhysicalPointToContinuousIndex(p, c);
    for (unsigned a = 0; a < 3; ++a) {
      cLo[a] = std::min(cLo[a], c[a]);
      cHi[a] = std::max(cHi[a], c[a]);
    }
  }
  std::array<long, 3> lo{}, hi{}, inStart{}, inSize{};
  for (unsigned a = 0; a < 3; ++a) {
    inStart[a] = long(inRegion.GetIndex()[a]);
    inSize[a] = long(inRegion.GetSize()[a]);
    lo[a] = std::max(inStart[a], long(std::floor(cLo[a])));
    hi[a] = std::min(inStart[a] + inSize[a] - 1, long(std::ceil(cHi[a])));
    if (lo[a] > hi[a]) return out; // the simulated box misses the input
  }

  // u: the input voxel centre in simulated voxel units. An exactly diagonal input (every axial CT) has it per
  // axis from a table, the same numbers as the per-voxel transform (see separable()).
  // Per axis, from u: inside the simulated box, the nearest simulated index, and whether u lies on it.
  auto inBox = [&](unsigned a, double ua) { return ua >= -0.5 && ua <= double(n[a]) - 0.5; };
  auto nearest = [&](unsigned a, double ua) { return std::clamp(std::lround(ua), 0L, n[a] - 1); };
  auto onIt = [](double ua, long na) { return std::abs(ua - double(na)) <= 1e-6; };
  const bool perAxis = separable(input);
  std::array<std::vector<double>, 3> along;
  std::array<std::vector<long>, 3> nearAlong;
  std::array<std::vector<std::uint8_t>, 3> insideAlong, centreAlong;
  if (perAxis)
    for (unsigned a = 0; a < 3; ++a) {
      along[a] = centresAlong(input, a, lo[a], hi[a] - lo[a] + 1);
      for (double& x : along[a]) {
        x = (x - o[a]) / h[a];
        insideAlong[a].push_back(inBox(a, x));
        nearAlong[a].push_back(nearest(a, x));
        centreAlong[a].push_back(onIt(x, nearAlong[a].back()));
      }
    }
  if (perAxis && voxelForVoxel(lo, hi, inStart, inSize, n, insideAlong, centreAlong, nearAlong)) {
    // The simulated CT covers the input voxel for voxel (a whole-scan region): the loop below would take
    // every voxel's own branch (on a centre, the same index); the same sums, without the index work.
    for (std::size_t v = 0; v < simCount; ++v) dst[v] = float(double(sim[v]) + (double(in[v]) - double(bg[v])));
    return out;
  }
  imaging::ImageType::IndexType index;
  for (index[2] = lo[2]; index[2] <= hi[2]; ++index[2])
    for (index[1] = lo[1]; index[1] <= hi[1]; ++index[1])
      for (index[0] = lo[0]; index[0] <= hi[0]; ++index[0]) {
        std::array<double, 3> u{};
        std::array<long, 3> near{};
        bool inside = true, onCentre = true;
        if (perAxis) {
          for (unsigned a = 0; a < 3; ++a) {
            const std::size_t t = std::size_t(index[a] - lo[a]);
            u[a] = along[a][t];
            near[a] = nearAlong[a][t];
            inside = inside && insideAlong[a][t];
            onCentre = onCentre && centreAlong[a][t];
          }
        } else {
          imaging::ImageType::PointType p;
          input->TransformIndexToPhysicalPoint(index, p);
          for (unsigned a = 0; a < 3; ++a) {
            u[a] = (p[a] - o[a]) / h[a];
            inside = inside && inBox(a, u[a]);
            near[a] = nearest(a, u[a]);
            onCentre = onCentre && onIt(u[a], near[a]);
          }
        }
        if (!inside) continue;
        const std::size_t target = std::size_t((index[0] - inStart[0]) +
                                               inSize[0] * ((index[1] - inStart[1]) + inSize[1] * (index[2] - inStart[2])));
        if (target >= inCount) continue; // cannot happen (lo/hi are clipped); never write outside the buffer
        const double inHu = in[target];
        if (onCentre) {
          // The same voxel: simulated + (input - background), which is the simulated HU itself wherever the
          // input equals the background (axial and reoriented CTs), with no round-off of a difference.
          const std::size_t v = simOffset(near[0], near[1], near[2]);
          if (v >= simCount) continue;
          dst[target] = float(double(sim[v]) + (inHu - double(bg[v])));
          continue;
        }
        // Oblique: the change, trilinear between the simulated voxel centres (clamped at the box's edge,
        // where the nearest centres are all there is).
        std::array<long, 3> i0{};
        std::array<double, 3> f{};
        for (unsigned a = 0; a < 3; ++a) {
          const double uc = std::clamp(u[a], 0.0, double(n[a] - 1));
          i0[a] = std::min(long(std::floor(uc)), std::max(0L, n[a] - 2));
          f[a] = n[a] > 1 ? uc - double(i0[a]) : 0.0;
        }
        double change = 0;
        for (int c = 0; c < 8; ++c) {
          double w = 1;
          std::array<long, 3> q{};
          for (unsigned a = 0; a < 3; ++a) {
            const bool up = (c >> a) & 1;
            w *= up ? f[a] : 1.0 - f[a];
            q[a] = std::min(i0[a] + (up ? 1 : 0), n[a] - 1);
          }
          if (w == 0.0) continue;
          const std::size_t v = simOffset(q[0], q[1], q[2]);
          if (v >= simCount) continue;
          change += w * (double(sim[v]) - double(bg[v]));
        }
        dst[target] = float(inHu + change);
      }
  return out;
}

} // namespace cementsph::scene
