#include "DrrOptions.h"

#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"

#include <vtkDataArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkImageShiftScale.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace cementsph::app {

void addDrrGeometryOptions(CLI::App& sub, DrrGeometryArgs& a, const std::string& sizeHelp) {
  auto& g = a.geometry;
  sub.add_option("--sad-mm", g.sadMm, "Source-axis distance, mm")->capture_default_str();
  sub.add_option("--sid-mm", g.sidMm, "Source-image (detector) distance, mm")->capture_default_str();
  sub.add_option("--detector-pixels", a.pixels, "Detector resolution in pixels: rows,cols")
      ->delimiter(',')
      ->expected(2)
      ->capture_default_str();
  a.sizeOption = sub.add_option("--detector-size-mm", a.sizeMm, sizeHelp)->delimiter(',')->expected(2);
  sub.add_option("--isocenter-mm", a.isocenterMm,
                 "Isocentre in the volume's physical coordinates, mm: x,y,z (default: the volume's centre)")
      ->delimiter(',')
      ->expected(3);
  sub.add_option("--gantry-angle-deg", g.gantryAngleDeg,
                 "Gantry angle about z, degrees (0: source on +x, 90: source on -y; plastimatch's sense)")
      ->capture_default_str();
  sub.add_flag("--parallel", g.parallel, "Parallel beam along the beam axis (sad/sid unused)");
  sub.add_option("--threads", a.threads, "OpenMP threads (0: the cores the load average leaves free)")->capture_default_str();
}

namespace {

// The geometry's own words name the quantity; the user typed an option: name it first.
[[noreturn]] void refuseGeometry(const std::string& problem) {
  const char* option = problem.find("source-image") != std::string::npos   ? "--sid-mm"
                       : problem.find("source-axis") != std::string::npos  ? "--sad-mm"
                       : problem.find("pixels") != std::string::npos       ? "--detector-pixels"
                       : problem.find("detector size") != std::string::npos ? "--detector-size-mm"
                                                                            : "";
  throw std::runtime_error(*option ? std::string(option) + ": " + problem : problem);
}

} // namespace

drr::DRRGeometry checkedGeometry(const DrrGeometryArgs& a) {
  if (a.threads < 0) throw std::runtime_error("--threads must be 0 or more");
  // A flat-panel detector has about 3000 pixels a side: 8192 leaves room, and 46341 x 46341 (2^31 pixels, 8 GB
  // of doubles) ran for minutes before running out of memory.
  constexpr int kMaxDetectorPixels = 8192;
  if (a.pixels[0] > kMaxDetectorPixels || a.pixels[1] > kMaxDetectorPixels)
    throw std::runtime_error("--detector-pixels " + std::to_string(a.pixels[0]) + "," + std::to_string(a.pixels[1]) +
                             ": at most " + std::to_string(kMaxDetectorPixels) +
                             " a side (a flat-panel detector has about 3000)");
  drr::DRRGeometry g = a.geometry;
  g.rows = a.pixels[0];
  g.cols = a.pixels[1];
  g.heightMm = a.sizeMm[0];
  g.widthMm = a.sizeMm[1];
  if (const std::string problem = g.validate(); !problem.empty()) refuseGeometry(problem);
  return g;
}

drr::DRRGeometry geometryForVolume(const DrrGeometryArgs& a, const std::array<double, 6>& b, bool fitDetector) {
  drr::DRRGeometry g = checkedGeometry(a);
  if (a.isocenterMm.empty())
    g.isocenterMm = {0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5])};
  else
    g.isocenterMm = {a.isocenterMm[0], a.isocenterMm[1], a.isocenterMm[2]};
  // A cone beam's source must lie outside the volume, in front of all of it: one inside (--sad-mm 1e-300) drew
  // a DRR of rays that start within the CT, without a word.
  if (!g.parallel) {
    const auto beam = g.beamDirection();
    for (int c = 0; c < 8; ++c) {
      const double rel[3] = {b[(c & 1) ? 1 : 0] - g.isocenterMm[0], b[(c & 2) ? 3 : 2] - g.isocenterMm[1],
                             b[(c & 4) ? 5 : 4] - g.isocenterMm[2]};
      if (!(g.sadMm + rel[0] * beam[0] + rel[1] * beam[1] + rel[2] * beam[2] > 0))
        throw std::runtime_error("--sad-mm " + std::to_string(g.sadMm) + ": the source lies inside or behind the volume "
                                 "(seen from the isocentre); give a --sad-mm larger than the volume's reach");
    }
  }
  try {
    if (fitDetector) g.fitDetectorTo(b, 1.1);
  } catch (const std::invalid_argument& e) {
    // The geometry names no option (and its own name is no help): say which ones place the source.
    std::string why = e.what();
    if (why.rfind("fitDetectorTo: ", 0) == 0) why.erase(0, 15);
    throw std::runtime_error("--sad-mm " + std::to_string(g.sadMm) + " with --isocenter-mm and --gantry-angle-deg: cannot fit "
                             "the detector to the volume (" + why + "); give a larger --sad-mm or an isocentre "
                             "inside the volume");
  }
  if (const std::string problem = g.validate(); !problem.empty()) throw std::runtime_error(problem);
  return g;
}

vtkSmartPointer<vtkImageData> viewAsVtk(const imaging::ImageType* volume) {
  if (volume == nullptr) throw std::runtime_error("viewAsVtk: no volume");
  const auto region = volume->GetBufferedRegion();
  const auto size = region.GetSize();
  auto view = vtkSmartPointer<vtkImageData>::New();
  view->SetDimensions(static_cast<int>(size[0]), static_cast<int>(size[1]), static_cast<int>(size[2]));
  // The buffered region may not start at index 0: its first voxel's position is the VTK origin.
  imaging::PointType start;
  volume->TransformIndexToPhysicalPoint(region.GetIndex(), start);
  double direction[9];
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j) direction[3 * i + j] = volume->GetDirection()[i][j];
  view->SetOrigin(start[0], start[1], start[2]);
  view->SetSpacing(volume->GetSpacing()[0], volume->GetSpacing()[1], volume->GetSpacing()[2]);
  view->SetDirectionMatrix(direction);
  auto voxels = vtkSmartPointer<vtkFloatArray>::New();
  // save = 1: VTK never frees (or writes) ITK's buffer; the const_cast is safe because the DRR only reads.
  voxels->SetArray(const_cast<float*>(volume->GetBufferPointer()),
                   static_cast<vtkIdType>(region.GetNumberOfPixels()), 1);
  view->GetPointData()->SetScalars(voxels);
  return view;
}

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

double drrWindow(const drr::XraySequence& sequence) {
  double top = 0.0;
  for (const auto& f : sequence.frames()) {
    double range[2];
    f.drr->GetPointData()->GetScalars()->GetRange(range, 0);
    top = std::max(top, range[1]);
  }
  return top;
}

void writeDrrFrames(const drr::XraySequence& sequence, const char* prefix, const std::string& dir) {
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

} // namespace cementsph::app
