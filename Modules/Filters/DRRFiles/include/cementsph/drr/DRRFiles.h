// The files a DRR becomes: `cementsph drr`'s drr.nrrd and drr.png, `cementsph xray`'s frames. One definition of
// the windowed X-ray picture, beside the DRR it draws, so the commands only name the folder.
#pragma once

#include "cementsph/drr/XraySequence.h"

#include <string>

class vtkImageData;

namespace cementsph::drr {

// A DRR as an 8-bit picture, written atomically: line integrals mapped linearly from [0, windowMax] to
// [255, 0] (dense = dark, as a C-arm monitor shows it and as xray_frames.png draws it: one convention in every
// X-ray picture); windowMax <= 0: the image's own maximum.
void writeDrrPng(vtkImageData* drr, const std::string& path, double windowMax = 0.0);

// `cementsph drr`'s files: creates the folder out, writes out/drr.nrrd (float, uncompressed: deflate would cost
// ~0.04 s of a 0.5 s run) and out/drr.png. If a write fails, what this call made goes again (the numbers, and
// the folder if it created it): no half output.
void writeDrrFiles(vtkImageData* drr, const std::string& out);

// The largest DRR value over a sequence's frames: one window for all its pictures.
double drrWindow(const XraySequence& sequence);

// `cementsph xray`'s frames: DIR/PREFIX_drr_NNNN.nrrd (float DRR) and .png, one window for the whole sequence.
void writeDrrFrames(const XraySequence& sequence, const char* prefix, const std::string& dir);

} // namespace cementsph::drr
