// `cementsph drr`: a digitally reconstructed radiograph of a CT volume with plastimatch's geometry and
// HU-to-attenuation conventions (so `plastimatch drr -i exact` images compare pixel for pixel).
// Writes DIR/drr.nrrd (float line integrals / 10, the numbers) and DIR/drr.png (8-bit picture,
// window [0, max]); neither needs a display or a GL context. A thin layer over CementSPH::DRR and
// CementSPH::ImagingIO. Everything is checked and computed before anything is written, and each file
// is written atomically.
#include "CommandRegistry.h"

#include "cementsph/drr/vtkDRRFilter.h"
#include "cementsph/imaging/AtomicFile.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"

#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkImageShiftScale.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

namespace {

namespace fs = std::filesystem;
using namespace cementsph::imaging;

struct DrrArgs {
  std::string volume, out;
  cementsph::drr::DRRGeometry geometry;
  std::vector<int> pixels{512, 512};
  std::vector<double> sizeMm{400.0, 400.0};
  std::vector<double> isocenterMm;
  int threads = 0;
};

// drr.png: the line integrals mapped linearly from [0, max] to [0, 255], written atomically.
void writeDrrPng(vtkImageData* drr, const std::string& path) {
  double range[2];
  drr->GetPointData()->GetScalars()->GetRange(range, 0);
  vtkNew<vtkImageShiftScale> toBytes;
  toBytes->SetInputData(drr);
  toBytes->SetShift(0.0);
  toBytes->SetScale(range[1] > 0.0 ? 255.0 / range[1] : 0.0);
  toBytes->SetOutputScalarTypeToUnsignedChar();
  toBytes->ClampOverflowOn();
  writeAtomically(path, [&](const std::string& tmp) {
    vtkNew<vtkPNGWriter> writer;
    writer->SetInputConnection(toBytes->GetOutputPort());
    writer->SetFileName(tmp.c_str());
    writer->Write();
    if (writer->GetErrorCode() != 0) throw std::runtime_error("PNG writer failed");
  });
}

cementsph::app::CommandRunner setupDrr(CLI::App& sub) {
  auto a = std::make_shared<DrrArgs>();
  auto& g = a->geometry;
  sub.add_option("--volume", a->volume, "CT volume in HU (file: .nrrd .mha .nii .nii.gz, or DICOM directory)")
      ->required();
  sub.add_option("--out", a->out, "Output directory (created): drr.nrrd and drr.png")->required();
  sub.add_option("--sad-mm", g.sadMm, "Source-axis distance, mm")->capture_default_str();
  sub.add_option("--sid-mm", g.sidMm, "Source-image (detector) distance, mm")->capture_default_str();
  sub.add_option("--detector-pixels", a->pixels, "Detector resolution in pixels: rows,cols")
      ->delimiter(',')
      ->expected(2)
      ->capture_default_str();
  sub.add_option("--detector-size-mm", a->sizeMm, "Detector physical size, mm: height,width")
      ->delimiter(',')
      ->expected(2)
      ->capture_default_str();
  sub.add_option("--isocenter-mm", a->isocenterMm,
                 "Isocentre in the volume's physical coordinates, mm: x,y,z (default: the volume's centre)")
      ->delimiter(',')
      ->expected(3);
  sub.add_option("--gantry-angle-deg", g.gantryAngleDeg,
                 "Gantry angle about z, degrees (0: source on +x, 90: source on -y; plastimatch's sense)")
      ->capture_default_str();
  sub.add_flag("--parallel", g.parallel, "Parallel beam along the beam axis (sad/sid unused)");
  sub.add_option("--threads", a->threads, "OpenMP threads (0: OpenMP's default)")->capture_default_str();

  return [a]() {
    const auto start = std::chrono::steady_clock::now();
    auto& geometry = a->geometry;
    geometry.rows = a->pixels[0];
    geometry.cols = a->pixels[1];
    geometry.heightMm = a->sizeMm[0];
    geometry.widthMm = a->sizeMm[1];
    if (a->threads < 0) throw std::runtime_error("--threads must be 0 or more");
    // Refuse a bad geometry before reading anything (the same check the filter makes).
    if (const std::string problem = geometry.validate(); !problem.empty()) throw std::runtime_error(problem);

    auto seconds = [](std::chrono::steady_clock::time_point since) {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
    };
    const ImageType::Pointer ct = readVolume(a->volume);
    const double readSeconds = seconds(start);
    const VolumeGeometry vg = geometryOf(ct);
    if (a->isocenterMm.empty()) {
      const auto b = vg.physicalBounds();
      geometry.isocenterMm = {0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5])};
    } else {
      geometry.isocenterMm = {a->isocenterMm[0], a->isocenterMm[1], a->isocenterMm[2]};
    }
    if (const std::string problem = geometry.validate(); !problem.empty()) throw std::runtime_error(problem);

    auto t = std::chrono::steady_clock::now();
    vtkSmartPointer<vtkImageData> hu = toVtk(ct.GetPointer());
    const double bridgeSeconds = seconds(t);
    vtkNew<vtkDRRFilter> drr;
    drr->SetInputData(hu);
    drr->SetSourceAxisDistance(geometry.sadMm);
    drr->SetSourceImageDistance(geometry.sidMm);
    drr->SetDetectorRows(geometry.rows);
    drr->SetDetectorColumns(geometry.cols);
    drr->SetDetectorHeight(geometry.heightMm);
    drr->SetDetectorWidth(geometry.widthMm);
    drr->SetIsocenter(geometry.isocenterMm.data());
    drr->SetGantryAngle(geometry.gantryAngleDeg);
    drr->SetParallelBeam(geometry.parallel);
    drr->SetNumberOfThreads(a->threads);
    // VTK errors become this command's one-line error (an observer also keeps VTK from printing them).
    std::string vtkError;
    vtkNew<vtkCallbackCommand> onError;
    onError->SetClientData(&vtkError);
    onError->SetCallback([](vtkObject*, unsigned long, void* client, void* callData) {
      std::string text = callData ? static_cast<const char*>(callData) : "";
      while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
      const auto colon = text.rfind("): "); // "...vtkDRRFilter (0x...): message"
      *static_cast<std::string*>(client) = colon == std::string::npos ? text : text.substr(colon + 3);
    });
    drr->AddObserver(vtkCommand::ErrorEvent, onError);
    t = std::chrono::steady_clock::now();
    drr->Update();
    const double drrSeconds = seconds(t);
    if (!vtkError.empty() || !drr->GetOutput()->GetPointData()->GetScalars())
      throw std::runtime_error("the DRR could not be computed" + (vtkError.empty() ? "" : ": " + vtkError));
    vtkImageData* image = drr->GetOutput();

    // Write: directory, numbers, picture. If a write fails, what this run made goes again (the numbers,
    // and the directory if it created it): no half output.
    t = std::chrono::steady_clock::now();
    const fs::path out(a->out);
    std::error_code ec;
    const bool madeDirectory = !fs::exists(out, ec);
    fs::create_directories(out, ec);
    if (ec) throw std::runtime_error(a->out + ": cannot create output directory: " + ec.message());
    const std::string nrrd = (out / "drr.nrrd").string(), png = (out / "drr.png").string();
    bool wroteNrrd = false;
    try {
      writeVolume(imageFromVtk(image), nrrd);
      wroteNrrd = true;
      writeDrrPng(image, png);
    } catch (...) {
      if (wroteNrrd) fs::remove(nrrd, ec);
      if (madeDirectory) fs::remove(out, ec); // only if empty
      throw;
    }

    double range[2];
    image->GetPointData()->GetScalars()->GetRange(range, 0);
    const double writeSeconds = seconds(t), total = seconds(start);
    std::ostringstream s;
    s << "DRR " << geometry.rows << "x" << geometry.cols << " px ("
      << (geometry.parallel ? "parallel beam" : "cone beam") << ", gantry " << geometry.gantryAngleDeg
      << " deg, isocentre " << geometry.isocenterMm[0] << "," << geometry.isocenterMm[1] << ","
      << geometry.isocenterMm[2] << " mm): max " << range[1] << " (line integral of mu in 1/mm, / 10)\n"
      << "wrote " << nrrd << " and " << png << " (read " << readSeconds << " s, ITK->VTK " << bridgeSeconds
      << " s, DRR " << drrSeconds << " s, write " << writeSeconds << " s, total " << total << " s)\n";
    std::cout << s.str();
    return 0;
  };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(drr_command, "drr",
                           "Digitally reconstructed radiograph of a CT volume (plastimatch geometry)",
                           setupDrr)
