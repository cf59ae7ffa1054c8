// `cementsph drr`: a digitally reconstructed radiograph of a CT volume with plastimatch's geometry and
// HU-to-attenuation conventions (so `plastimatch drr -i exact` images compare pixel for pixel).
// Writes DIR/drr.nrrd (float line integrals / 10, the numbers) and DIR/drr.png (8-bit picture,
// window [0, max], dense matter dark as in every X-ray picture the program writes); neither needs a display
// or a GL context. A thin layer over CementSPH::DRR and
// CementSPH::ImagingIO. Everything is checked and computed before anything is written, and each file
// is written atomically.
#include "CommandRegistry.h"
#include "DrrOptions.h"

#include "cementsph/drr/DRRFiles.h"
#include "cementsph/drr/ProjectVolume.h"
#include "cementsph/drr/VolumeView.h"
#include "cementsph/imaging/ItkVtkBridge.h"
#include "cementsph/imaging/VolumeIO.h"

#include <vtkDataArray.h>
#include <vtkImageData.h>
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
  cementsph::app::DrrGeometryArgs drr;
};

cementsph::app::CommandRunner setupDrr(CLI::App& sub) {
  auto a = std::make_shared<DrrArgs>();
  sub.add_option("--volume", a->volume, "CT volume in HU (file: .nrrd .mha .nii .nii.gz, or DICOM directory)")
      ->required();
  sub.add_option("--out", a->out, "Output directory (created): drr.nrrd and drr.png")->required();
  cementsph::app::addDrrGeometryOptions(sub, a->drr, "Detector physical size, mm: height,width [400,400]");
  // Side by side with plastimatch (docs/drr-figures.md): the two differ in the isocentre's default and in the
  // row order of the files, nothing else in the geometry.
  sub.footer("To compare with `plastimatch drr -i exact`: give plastimatch's isocentre (its default is 0,0,0; ours is "
             "the volume's centre) with --isocenter-mm, the same --sad-mm/--sid-mm (its -g \"sad sid\"), "
             "--detector-pixels (its -r \"rows cols\") and --detector-size-mm (its -z), and flip rows: plastimatch's "
             "PFM stores the top row first, drr.nrrd the bottom row first (VTK's order; drr.png is drawn top up). "
             "Pixel values use plastimatch's scaling (sum of mu * length / 10).");

  return [a]() {
    const auto start = std::chrono::steady_clock::now();
    // Refuse a bad geometry before reading anything (the same check the filter makes).
    (void)cementsph::app::checkedGeometry(a->drr);

    auto seconds = [](std::chrono::steady_clock::time_point since) {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
    };
    const ImageType::Pointer ct = readVolume(a->volume);
    const double readSeconds = seconds(start);
    const cementsph::drr::DRRGeometry geometry =
        cementsph::app::geometryForVolume(a->drr, geometryOf(ct).physicalBounds(), false);

    auto t = std::chrono::steady_clock::now();
    vtkSmartPointer<vtkImageData> hu = cementsph::drr::viewAsVtk(ct.GetPointer());
    const double bridgeSeconds = seconds(t);
    t = std::chrono::steady_clock::now();
    const vtkSmartPointer<vtkImageData> image = cementsph::drr::projectVolume(hu, geometry, a->drr.threads);
    const double drrSeconds = seconds(t);

    // Write: directory, numbers, picture; a failed write leaves no half output.
    t = std::chrono::steady_clock::now();
    cementsph::drr::writeDrrFiles(image, a->out);
    const std::string nrrd = (fs::path(a->out) / "drr.nrrd").string(), png = (fs::path(a->out) / "drr.png").string();

    double range[2];
    image->GetPointData()->GetScalars()->GetRange(range, 0);
    const double writeSeconds = seconds(t), total = seconds(start);
    std::ostringstream s;
    s << "DRR " << geometry.rows << "x" << geometry.cols << " px ("
      << (geometry.parallel ? "parallel beam" : "cone beam") << ", gantry " << geometry.gantryAngleDeg
      << " deg, isocentre " << geometry.isocenterMm[0] << "," << geometry.isocenterMm[1] << ","
      << geometry.isocenterMm[2] << " mm): max " << range[1] << " (line integral of mu in 1/mm, / 10)\n"
      << "wrote " << nrrd << " and " << png << " (read " << readSeconds << " s, ITK->VTK view " << bridgeSeconds
      << " s, DRR " << drrSeconds << " s, write " << writeSeconds << " s, total " << total << " s)\n";
    std::cout << s.str();
    return 0;
  };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(drr_command, "drr",
                           "Digitally reconstructed radiograph of a CT volume (plastimatch geometry)",
                           setupDrr)
