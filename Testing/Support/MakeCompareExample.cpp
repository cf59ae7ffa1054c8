// Writes the small pre/post/simulated CT example shipped in Data/compare-example, so that the README's
// `cementsph compare` command runs on real-format inputs: the pre scan as NRRD, the post scan as a
// DICOM series (a directory, stored with the usual Rescale Intercept -1024), the simulated CT as NRRD,
// and the injection point and the true misalignment as JSON. Reproducible: fixed seeds.
//   make-compare-example DIR
#include "SyntheticVolumes.h"

#include "cementsph/imaging/VolumeIO.h"

#include <filesystem>
#include <fstream>
#include <iostream>

int main(int argc, char** argv) {
  using namespace cementsph;
  if (argc != 2) {
    std::cerr << "usage: make-compare-example DIR\n";
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  const std::filesystem::path scratch = dir / "scratch";
  std::filesystem::create_directories(scratch);
  testing::CompareCase c;
  c.grid.size = {64, 64, 60};
  c.grid.spacing = {0.47, 0.47, 0.5}; // the paper's CT voxels
  c.semiAxesMm = {13, 12.5, 13};
  c.cementRadiusMm = 5.5;
  c.simRadiusMm = 6.0;
  const testing::Vec3 tip = testing::writeCompareCase(c, scratch.string());
  std::filesystem::rename(scratch / "pre.nrrd", dir / "pre.nrrd");
  std::filesystem::rename(scratch / "sim.nrrd", dir / "simulated.nrrd");
  const auto post = imaging::readVolume((scratch / "post.nrrd").string());
  std::filesystem::remove_all(dir / "post_dicom");
  imaging::writeDicomSeries(post, (dir / "post_dicom").string(), -1024.0);
  std::filesystem::remove_all(scratch);
  std::ofstream truth(dir / "truth.json");
  truth << "{\n  \"injection_point_mm\": [" << tip[0] << ", " << tip[1] << ", " << tip[2] << "],\n"
        << "  \"misalignment_rotation_deg\": [" << c.rotationDeg[0] << ", " << c.rotationDeg[1] << ", "
        << c.rotationDeg[2] << "],\n"
        << "  \"misalignment_scale\": [" << c.scale[0] << ", " << c.scale[1] << ", " << c.scale[2] << "],\n"
        << "  \"misalignment_translation_mm\": [" << c.translationMm[0] << ", " << c.translationMm[1] << ", "
        << c.translationMm[2] << "],\n"
        << "  \"cement_radius_mm\": " << c.cementRadiusMm << ",\n  \"simulated_radius_mm\": " << c.simRadiusMm
        << ",\n  \"simulated_offset_x_mm\": " << c.simOffsetMm << "\n}\n";
  std::cout << "injection point (mm): " << tip[0] << "," << tip[1] << "," << tip[2] << "\n";
  return 0;
}
