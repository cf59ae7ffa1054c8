// The vertebra phantom's anatomy variant that the leak suites share (VertebraLeakTest, CapillaryLeakTest): a
// 64 x 70 x 57 mm field with a 5 mm sphere of marrow fat, 10 mm discs above and below the body and a 2 mm
// basivertebral vein. Its centre is (fieldMm[0] / 2, 21, fieldMm[2] / 2) (VertebraPhantom.cpp).
#pragma once

#include "cementsph/phantom/VertebraPhantom.h"

namespace cementsph::testing {

inline phantom::VertebraOptions vertebraAnatomyVariant() {
  phantom::VertebraOptions o;
  o.fieldMm = {64, 70, 57};
  o.marrowFatRadiusMm = 5;
  o.discHeightMm = 10;
  o.veinRadiusMm = 2;
  return o;
}

} // namespace cementsph::testing
