// The simulated CT of an injection (Basafa et al. 2013, "Simulations"): the CT's grid within the region of
// interest, HU_sim = HU_pre + k rho_fluid / rho0, rho_fluid the Eq. 2 fluid density at each voxel centre
// (ParticleVoxeliser, h = 2r), k the HU that cement at rest density adds (3000 HU by default). Used for the
// final simulated_ct.nrrd and, with the scene key simulated_ct_snapshots, for every snapshot.
#pragma once

#include "cementsph/imaging/ImageTypes.h"
#include "cementsph/scene/PorousSolid.h"

#include <cstddef>
#include <utility>
#include <vector>

namespace cementsph::scene {

// fluidDensity: kg/m^3 per ROI voxel in solid.grid.index order (ParticleVoxeliser::density on solid.grid);
// an empty vector means no fluid (the result is the CT's ROI unchanged). restDensity rho0 in kg/m^3.
imaging::ImageType::Pointer simulatedCtOnRoi(const imaging::ImageType* ct, const PorousSolid& solid,
                                             const std::vector<double>& fluidDensity, double huPerRelativeDensity,
                                             double restDensity);

// A density where it is not zero: (ROI voxel in solid.grid.index order, kg/m^3), the voxels in increasing order;
// every other voxel has none. Sized to the cement, not the region (issue 23: a dense density of a whole-scan
// region was 8 bytes a voxel at the run's end).
using SparseDensity = std::vector<std::pair<std::size_t, double>>;
SparseDensity nonZeroDensity(const std::vector<double>& density);

// The same simulated CT from a sparse density: every voxel's value is the dense version's (as a number: a voxel
// with no cement keeps the CT's value bit for bit, where the dense pass, adding 0, turns a CT's -0 HU into +0).
imaging::ImageType::Pointer simulatedCtOnRoi(const imaging::ImageType* ct, const PorousSolid& solid,
                                             const SparseDensity& fluidDensity, double huPerRelativeDensity,
                                             double restDensity);

} // namespace cementsph::scene
