// The DRR options and outputs that `cementsph drr` and `cementsph xray` share: one definition of the
// geometry options (names, units, help) and of the windowed PNG, so the two commands cannot drift apart.
#pragma once

#include "cementsph/drr/DRRGeometry.h"
#include "cementsph/drr/XraySequence.h"
#include "cementsph/imaging/ImageTypes.h"

#include <vtkSmartPointer.h>

#include <CLI/CLI.hpp>

#include <array>
#include <string>
#include <vector>

class vtkImageData;

namespace cementsph::app {

struct DrrGeometryArgs {
  drr::DRRGeometry geometry;           // sad, sid, gantry angle, parallel: set by the options directly
  std::vector<int> pixels{512, 512};   // rows, cols
  std::vector<double> sizeMm{400.0, 400.0}; // height, width
  std::vector<double> isocenterMm;     // empty: the volume's centre
  int threads = 0;
  CLI::Option* sizeOption = nullptr;   // to tell whether --detector-size-mm was given
};

// Adds --sad-mm, --sid-mm, --detector-pixels, --detector-size-mm, --isocenter-mm, --gantry-angle-deg,
// --parallel and --threads. sizeHelp: the help of --detector-size-mm (its default differs by command).
void addDrrGeometryOptions(CLI::App& sub, DrrGeometryArgs& args, const std::string& sizeHelp);

// The geometry the options give before any volume is read (isocentre still at the origin). Throws
// std::runtime_error with DRRGeometry::validate()'s sentence, or for negative --threads.
drr::DRRGeometry checkedGeometry(const DrrGeometryArgs& args);

// The geometry for a volume whose voxel centres span boundsMm ({xmin, xmax, ymin, ymax, zmin, zmax}): the
// isocentre is the box's centre unless --isocenter-mm was given; with fitDetector the detector size is
// fitted to the box's projection (DRRGeometry::fitDetectorTo, 10 % margin, square pixels). Throws
// std::runtime_error when the result is unusable.
drr::DRRGeometry geometryForVolume(const DrrGeometryArgs& args, const std::array<double, 6>& boundsMm, bool fitDetector);

// The CT's voxels seen as a vtkImageData without copying them (geometry as imaging::toVtk gives it):
// the DRR only reads them, and a 256x256x200 copy was a tenth of a whole `cementsph drr` run (the copy and
// its page faults). `volume` must outlive the view.
vtkSmartPointer<vtkImageData> viewAsVtk(const imaging::ImageType* volume);

// A DRR as an 8-bit picture, written atomically: line integrals mapped linearly from [0, windowMax] to
// [255, 0] (dense = dark, as a C-arm monitor shows it and as xray_frames.png draws it: one convention in every
// X-ray picture); windowMax <= 0: the image's own maximum.
void writeDrrPng(vtkImageData* drr, const std::string& path, double windowMax = 0.0);
// `cementsph drr`'s files: creates the folder out, writes out/drr.nrrd (float, uncompressed: deflate would cost
// ~0.04 s of a 0.5 s run) and out/drr.png. If a write fails, what this call made goes again (the numbers, and
// the folder if it created it): no half output.
void writeDrrFiles(vtkImageData* drr, const std::string& out);
// The largest DRR value over a sequence's frames: one window for all its pictures.
double drrWindow(const drr::XraySequence& sequence);
// `cementsph xray`'s frames: DIR/PREFIX_drr_NNNN.nrrd (float DRR) and .png, one window for the whole sequence.
void writeDrrFrames(const drr::XraySequence& sequence, const char* prefix, const std::string& dir);

} // namespace cementsph::app
