// The CT-to-porous-solid step of an injection scene: a 20^3 CT of 1 mm voxels, bone (1000 HU) in the five
// voxel layers x < 5, air (-1000 HU) elsewhere, the tip at (12, 10, 10) mm and a 40 mm region that holds the
// whole CT. Counted by hand: 5 * 400 = 2000 solid voxels; the pore space connected to the tip is the other
// 15 * 400 = 6000 voxels; a solid voxel is kept when a pore voxel's centre lies within the 2.28 mm reach, which
// holds for the layers x = 3 (2 mm from x = 5) and x = 4 (1 mm), not x = 2 (3 mm; any sideways step only adds
// distance): 2 * 400 = 800; each fixed particle weighs rho0 * (1 mm)^3 = 1180 kg/m^3 * 1e-9 m^3.
#include "Checks.h"

#include "cementsph/scene/PorousSolid.h"

int checkCTScene() {
  using cementsph::imaging::ImageType;
  auto ct = ImageType::New();
  ImageType::RegionType region;
  region.SetSize({20, 20, 20});
  ct->SetRegions(region);
  ct->Allocate();
  for (unsigned k = 0; k < 20; ++k)
    for (unsigned j = 0; j < 20; ++j)
      for (unsigned i = 0; i < 20; ++i) ct->SetPixel({{i, j, k}}, i < 5 ? 1000.0f : -1000.0f);

  cementsph::scene::PorousSolidOptions options; // threshold 0 HU, reach 2.28 mm, rho0 1180 kg/m^3
  options.roiSizeMm = 40.0;
  const auto solid = cementsph::scene::buildPorousSolid(ct, Eigen::Vector3d(12.0, 10.0, 10.0), options);
  int failures = compare("porous solid, solid voxels", double(solid.solidVoxels), 2000.0, 0.0);
  failures += compare("porous solid, connected pore voxels", double(solid.connectedPoreVoxels), 6000.0, 0.0);
  failures += compare("porous solid, kept solid voxels", double(solid.keptVoxels), 800.0, 0.0);
  failures += compare("porous solid, fixed particles", double(solid.positions.size()), 800.0, 0.0);
  failures += compare("porous solid, particle mass, kg", solid.particleMass, 1180.0 * 1e-9, 1e-18);
  return failures;
}
