// `cementsph register`: affine registration of a post-injection CT onto the pre-injection CT
// (translation then affine, multi-resolution, cement masked out of the metric). A thin layer over
// CementSPH::Registration.
#include "CommandRegistry.h"

#include "cementsph/imaging/AffineRegistration.h"
#include "cementsph/imaging/VolumeIO.h"

#include <iostream>
#include <memory>

namespace {

struct RegisterArgs {
  std::string fixed, moving, transformOut, imageOut;
  bool noCementMask = false;
};

cementsph::app::CommandRunner setupRegister(CLI::App& sub) {
  auto args = std::make_shared<RegisterArgs>();
  sub.add_option("--fixed,--pre", args->fixed, "Fixed (pre-injection) CT: file or DICOM directory")
      ->required();
  sub.add_option("--moving,--post", args->moving, "Moving (post-injection) CT: file or DICOM directory")
      ->required();
  sub.add_option("--out-transform", args->transformOut,
                 "ITK transform file to write (.tfm, .h5, .mat); maps fixed to moving points (mm)")
      ->required();
  sub.add_option("--out-image", args->imageOut,
                 "Moving image resampled onto the fixed grid (.nrrd default; .mha, .nii, .nii.gz)");
  sub.add_flag("--no-cement-mask", args->noCementMask,
               "Do not exclude bright (cement) voxels of the moving image from the metric");
  return [args]() {
    using namespace cementsph::imaging;
    const auto fixed = readVolume(args->fixed);
    const auto moving = readVolume(args->moving);
    RegistrationOptions options;
    options.maskCement = !args->noCementMask;
    const RegistrationResult result = registerAffine(fixed, moving, options);
    writeTransform(result.transform, args->transformOut);
    if (!args->imageOut.empty()) writeVolume(resampleOnto(moving, fixed, result.transform), args->imageOut);
    std::cout << "registration (moving -> fixed):\n" << formatRegistrationReport(result);
    return 0;
  };
}

} // namespace

CEMENTSPH_REGISTER_COMMAND(register_command, "register",
                           "Affine registration of a post-injection CT onto the pre-injection CT",
                           setupRegister)
