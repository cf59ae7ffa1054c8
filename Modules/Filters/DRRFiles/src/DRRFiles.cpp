#include "cementsph/drr/DRRFiles.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkImageShiftScale.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace cementsph::drr {

void writeDrrPng(vtkImageData* drr, const std::string& path, double windowMax) {
  double range[2];
  drr->GetPointData()->GetScalars()->GetRange(range, 0);
  const double top = windowMax > 0.0 ? windowMax : range[1];
  // One convention in every X-ray picture the program writes (drr.png, the sequences' frames, xray_frames.png
  // of XrayFramesPicture.h): dense matter dark, as a C-arm monitor shows it: grey = 255 (1 - value / top),
  // clamped. All air (top 0) is white.
  const double window = top > 0.0 ? top : 1.0;
  vtkNew<vtkImageShiftScale> toBytes;
  toBytes->SetInputData(drr);
  toBytes->SetShift(-window);
  toBytes->SetScale(-255.0 / window);
  toBytes->SetOutputScalarTypeToUnsignedChar();
  toBytes->ClampOverflowOn();
  imaging::writeAtomically(path, [&](const std::string& tmp) {
    vtkNew<vtkPNGWriter> writer;
    writer->SetInputConnection(toBytes->GetOutputPort());
    writer->SetFileName(tmp.c_str());
    writer->Write();
    if (writer->GetErrorCode() != 0) throw std::runtime_error("PNG writer failed");
  });
}

void writeDrrFiles(vtkImageData* drr, const std::string& outDir) {
  namespace fs = std::filesystem;
  const fs::path out(outDir);
  std::error_code ec;
  const bool madeDirectory = !fs::exists(out, ec);
  fs::create_directories(out, ec);
  if (ec) throw std::runtime_error(outDir + ": cannot create output directory: " + ec.message());
  const std::string nrrd = (out / "drr.nrrd").string(), png = (out / "drr.png").string();
  bool wroteNrrd = false;
  try {
    imaging::writeVolume(imaging::imageFromVtk(drr), nrrd, /*compress=*/false);
    wroteNrrd = true;
    writeDrrPng(drr, png);
  } catch (...) {
    if (wroteNrrd) fs::remove(nrrd, ec);
    if (madeDirectory) fs::remove(out, ec); // only if empty
    throw;
  }
}

double drrWindow(const XraySequence& sequence) {
  double top = 0.0;
  for (const auto& f : sequence.frames()) {
    double range[2];
    f.drr->GetPointData()->GetScalars()->GetRange(range, 0);
    top = std::max(top, range[1]);
  }
  return top;
}

void writeDrrFrames(const XraySequence& sequence, const char* prefix, const std::string& dir) {
  const double window = drrWindow(sequence);
  for (std::size_t k = 0; k < sequence.frames().size(); ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "%s_drr_%04zu", prefix, k);
    const auto& frame = sequence.frames()[k];
    const std::filesystem::path base = std::filesystem::path(dir) / name;
    imaging::writeVolume(imaging::imageFromVtk(frame.drr), base.string() + ".nrrd");
    writeDrrPng(frame.drr, base.string() + ".png", window);
  }
}

} // namespace cementsph::drr
