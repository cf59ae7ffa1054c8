// The fixed particles' share of Eq. 2 and Eq. 5, tabulated on a grid (ours; not in the paper).
//
// Fixed particles never move and keep one density and pressure (the paper, "Particle Fluid Model"), so
// what they contribute to a fluid particle at x depends on x alone:
//   density  (Eq. 2):  D(x)   = sum_j m_j W_cubic(|x - x_j|)
//   pressure (Eq. 5):  a(x)   = -(p_i/rho_i^2 + p_s/rho_s^2) G(x),  G(x) = sum_j m_j grad W_spiky(x - x_j)
// In a CT scene a cement particle has ~120 solid voxels within its support; summing them every step is
// most of the work. Here D and G are summed exactly once at the nodes of a regular grid and
// interpolated trilinearly (second order where they are smooth). Interpolating G itself, not taking
// the gradient of an interpolated potential (first order), matters: on the phantom the spreading
// distance converged linearly in the spacing with the potential (0.25 mm off at h/3) - VALIDATION.md.
//
// The grid is filled lazily in bricks of kBrick^3 cells: only where cement goes (a few % of a 40 mm
// region) is ever summed. prepare() fills, in parallel, the bricks that contain a set of points;
// sample() is then read-only and thread safe. The accuracy against the exact sums is a test
// (Modules/Core/SPH/test) and the cost of the approximation on an injection is in VALIDATION.md.
#pragma once

#include "cementsph/sph/Domain.h"
#include "cementsph/sph/Kernels.h"
#include "cementsph/sph/NeighbourSearch.h"
#include "cementsph/sph/Particles.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace cementsph::sph {

// The sums over fixed particles at a point (what a node holds): D (cubic spline, Eq. 10) and G (spiky gradient, Eq. 11).
struct FixedSums {
  double density = 0.0;                // D [kg/m^3]
  double gradient[3] = {0.0, 0.0, 0.0}; // G [kg/m^4]; a fixed particle exactly at the point adds nothing
};

class FixedParticleField {
public:
  static constexpr int kBrick = 8; // cells per brick edge

  // A grid of nodes `nodeSpacing` apart from domain.lower, covering the domain (open axes only).
  void configure(const Domain& domain, double nodeSpacing, double smoothingLength);
  bool configured() const { return nodeSpacing_ > 0; }
  double nodeSpacing() const { return nodeSpacing_; }

  // The fixed particles the sums run over: binned by `grid` (cells >= the kernel support), cell c's
  // particles are [cellStart[c], cellStart[c+1]). Forgets every computed brick.
  void attach(const FixedParticles* fixed, const CellGrid* grid, const std::vector<std::uint32_t>* cellStart);
  // Sum the fixed particles' volumes instead of their masses (D is then the solid volume fraction the
  // incompressible model needs). Set before the first prepare().
  void weighByVolume(bool byVolume) { byVolume_ = byVolume; }

  // Fills the bricks containing the points that are not filled yet. Points must lie inside the domain.
  void prepare(const double* x, const double* y, const double* z, std::size_t n);
  // Trilinear D and G at a point of a prepared brick.
  void sample(double x, double y, double z, double& density, double gradient[3]) const;

  std::size_t bricksFilled() const { return filled_; }
  std::size_t bytesUsed() const { return filled_ * kNodesPerBrick * sizeof(FixedSums); }

private:
  static constexpr int kNodesPerEdge = kBrick + 1;
  static constexpr int kNodesPerBrick = kNodesPerEdge * kNodesPerEdge * kNodesPerEdge;
  std::size_t brickIndex(double x, double y, double z, int local[3], double frac[3]) const;
  void fillBrick(std::size_t b);

  Domain domain_;
  double nodeSpacing_ = 0.0, inverseSpacing_ = 0.0;
  std::int64_t bricksPerAxis_[3] = {0, 0, 0};
  double h_ = 0.0;
  const FixedParticles* fixed_ = nullptr;
  const CellGrid* grid_ = nullptr;
  const std::vector<std::uint32_t>* cellStart_ = nullptr;
  std::vector<std::unique_ptr<FixedSums[]>> bricks_; // null until filled
  std::size_t filled_ = 0;
  bool byVolume_ = false;
};

} // namespace cementsph::sph
