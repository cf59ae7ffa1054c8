// Fluid particles to a voxel density image, as the paper made its simulated CT volumes (Basafa et al. 2013,
// "Simulations"): "for each voxel, we found the neighboring fluid particles and used Eq. 2 to determine the
// fluid density at the center of the voxel ... A kernel radius of h = 2r was used here, where r is the
// initial radius of the fluid particles." With d = 2r (VALIDATION.md) that is h = d.
//
// rho(x_v) = sum_j m_j W(x_v - x_j, h), cubic spline (Eq. 10), at every voxel centre x_v. Particles are
// binned in cells of the kernel support 2h, so each voxel visits at most 27 cells; voxels run in parallel
// (OpenMP). Plain arrays, x fastest: index = i + nx (j + ny k). No VTK here.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <vector>

namespace cementsph::sph {

struct FluidParticles;

struct VoxelGrid {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // centre of voxel (0, 0, 0) [m]
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones(); // voxel size per axis [m]
  std::array<int, 3> size{1, 1, 1};                  // voxels per axis

  std::size_t count() const { return std::size_t(size[0]) * std::size_t(size[1]) * std::size_t(size[2]); }
  double voxelVolume() const { return spacing.prod(); }
  std::size_t index(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(size[0]) * (std::size_t(j) + std::size_t(size[1]) * std::size_t(k));
  }
  Eigen::Vector3d centre(int i, int j, int k) const {
    return origin + spacing.cwiseProduct(Eigen::Vector3d(i, j, k));
  }
};

class ParticleVoxeliser {
public:
  // h [m]: the kernel's smoothing length (the paper: h = 2r = d). Throws std::invalid_argument for a grid
  // with non-positive spacing or size, or a non-positive h.
  ParticleVoxeliser(const VoxelGrid& grid, double smoothingLength);

  const VoxelGrid& grid() const { return grid_; }
  double smoothingLength() const { return h_; }

  // Density [kg/m^3] at every voxel centre from positions and masses (n each).
  std::vector<double> density(const double* x, const double* y, const double* z, const double* mass,
                              std::size_t n) const;
  std::vector<double> density(const FluidParticles& fluid) const;
  // sum rho V_voxel [kg]: the mass the image holds (equals the particles' mass when the grid covers them and
  // resolves the kernel).
  double integratedMass(const std::vector<double>& density) const;

private:
  VoxelGrid grid_;
  double h_;
};

} // namespace cementsph::sph
