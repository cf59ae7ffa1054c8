// Volumes in and out: a 4 x 5 x 6 volume with voxel value i + 10 j + 100 k, anisotropic spacing and an
// off-zero origin, written to NRRD and read back. Every voxel must come back exactly (small integers are exact
// in float) and the geometry to 1e-9 mm; the voxel sum must equal the closed form
// nx ny nz ((nx - 1)/2 + 10 (ny - 1)/2 + 100 (nz - 1)/2) = 120 * (1.5 + 20 + 250) = 32580.
#include "Checks.h"

#include "cementsph/imaging/VolumeIO.h"

#include <cmath>
#include <cstdio>

int checkImagingIO() {
  using cementsph::imaging::ImageType;
  auto volume = ImageType::New();
  ImageType::RegionType region;
  region.SetSize({4, 5, 6});
  volume->SetRegions(region);
  const double spacing[3] = {0.5, 0.75, 1.25}, origin[3] = {-10.0, 20.0, 3.5};
  volume->SetSpacing(spacing);
  volume->SetOrigin(origin);
  volume->Allocate();
  for (unsigned k = 0; k < 6; ++k)
    for (unsigned j = 0; j < 5; ++j)
      for (unsigned i = 0; i < 4; ++i) volume->SetPixel({{i, j, k}}, float(i + 10 * j + 100 * k));

  const std::string path = "imagingio-check.nrrd"; // in the working directory (the consumer's build folder)
  cementsph::imaging::writeVolume(volume, path);
  const auto back = cementsph::imaging::readVolume(path);
  std::remove(path.c_str());

  int failures = 0;
  const auto size = back->GetLargestPossibleRegion().GetSize();
  failures += compare("NRRD round trip, voxels", double(size[0] * size[1] * size[2]), 120.0, 0.0);
  for (unsigned a = 0; a < 3; ++a) {
    failures += compare("NRRD round trip, spacing, mm", back->GetSpacing()[a], spacing[a], 1e-9);
    failures += compare("NRRD round trip, origin, mm", back->GetOrigin()[a], origin[a], 1e-9);
  }
  if (failures) return failures;
  double sum = 0.0;
  int mismatched = 0;
  for (unsigned k = 0; k < 6; ++k)
    for (unsigned j = 0; j < 5; ++j)
      for (unsigned i = 0; i < 4; ++i) {
        const double value = back->GetPixel({{i, j, k}});
        sum += value;
        mismatched += value != double(i + 10 * j + 100 * k);
      }
  failures += compare("NRRD round trip, voxels differing from i + 10 j + 100 k", mismatched, 0.0, 0.0);
  failures += compare("NRRD round trip, voxel sum", sum, 120.0 * (1.5 + 20.0 + 250.0), 0.0);
  return failures;
}
