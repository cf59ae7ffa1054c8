// CT to porous solid (Basafa et al. 2013, "Simulations": voxels above a threshold become fixed particles).
//
// Decisions (docs/scene-figures.md):
//  * Solid: HU > threshold (the paper: HU > 0).
//  * Region of interest: the voxels whose centres lie in the cube of edge roiSizeMm centred on the tip,
//    clipped to the CT. Only these are modelled; the simulation box is the ROI's voxel boxes.
//  * One fixed particle per solid voxel, at its centre, mass rho0 V_voxel (a fully solid neighbourhood then
//    sums to rho0 in Eq. 2).
//  * Kept voxels: a solid voxel is kept only if a pore voxel (of the ROI) has its centre within `reach`
//    (the kernel support 2h) of its centre; deeper solid can never be a neighbour of a fluid particle in the
//    pores. Kept and total solid counts are reported.
//  * Errors (std::invalid_argument, one line): tip outside the CT; tip in a solid voxel; pore space
//    connected to the tip (6-connected, within the ROI) smaller than `requiredPoreVolumeMm3` (a closed cavity
//    cannot take the injection).
//  * The CT's direction matrix must be the identity (axis-aligned grids, as the voxeliser's).
#pragma once

#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/sph/ParticleVoxeliser.h"

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <vector>

namespace cementsph::scene {

struct PorousSolidOptions {
  double thresholdHu = 0.0;
  double roiSizeMm = 40.0;
  double reachMm = 2.28;              // kernel support 2h [mm]
  double restDensity = 1180.0;        // rho0 [kg/m^3]
  double massFactor = 1.0;            // particle mass = factor rho0 V_voxel
  double requiredPoreVolumeMm3 = 0.0; // connected pore space about the tip must hold at least this
  // The kept solid voxels and their centres (the particle engines' fixed particles). false: positions stay
  // empty and keptVoxels 0 until keepSolidNearPores (the voxel engine needs neither: 24 bytes a kept voxel,
  // a region-sized pass).
  bool keptPositions = true;
};

struct PorousSolid {
  std::array<long, 3> roiStart{};     // first ROI voxel index in the CT
  std::array<long, 3> roiSize{};      // ROI voxels per axis
  sph::VoxelGrid grid;                // the ROI grid in metres (centre of voxel 0, spacing, size)
  std::vector<std::uint8_t> solid;    // per ROI voxel (grid.index order): HU > threshold
  std::vector<Eigen::Vector3d> positions; // kept solid voxel centres [m]
  double particleMass = 0.0;          // rho0 V_voxel [kg]
  std::size_t solidVoxels = 0;        // solid voxels in the ROI
  std::size_t keptVoxels = 0;         // of those, within reach of pore space
  std::size_t connectedPoreVoxels = 0; // pore voxels 6-connected to the tip's voxel
  Eigen::Vector3d lowerM, upperM;     // the ROI's outer box [m] (voxel boxes, not centres)
  Eigen::Vector3d spacingMm{0, 0, 0}; // the CT's voxel spacing [mm], as the reach is given

  // ROI voxel containing point p [m], or false when outside.
  bool voxelOf(const Eigen::Vector3d& p, std::array<int, 3>& ijk) const;
};

PorousSolid buildPorousSolid(const imaging::ImageType* ct, const Eigen::Vector3d& tipMm, const PorousSolidOptions& options);
// The kept solid voxels (within reachMm of a pore voxel's centre) into s.positions and s.keptVoxels;
// buildPorousSolid calls it unless options.keptPositions is false.
void keepSolidNearPores(PorousSolid& s, double reachMm);

} // namespace cementsph::scene
