#include "cementsph/study/AlignedPost.h"

#include "cementsph/imaging/VolumeIO.h"

#include <itkIdentityTransform.h>

#include <stdexcept>

namespace cementsph::study {

AlignedPost alignPostOntoPre(const imaging::ImageType* pre, const imaging::ImageType* post, bool registration,
                             const imaging::RegistrationOptions& options) {
  AlignedPost a;
  if (!registration) {
    if (imaging::overlapVolumeMm3(imaging::geometryOf(pre), imaging::geometryOf(post)) <= 0.0)
      throw std::runtime_error("the pre and post volumes do not overlap in space");
    auto identity = itk::IdentityTransform<double, 3>::New();
    a.volume = imaging::resampleOnto(post, pre, identity);
  } else {
    a.registration = imaging::registerAffine(pre, post, options);
    a.volume = imaging::resampleOnto(post, pre, a.registration->transform);
  }
  return a;
}

} // namespace cementsph::study
