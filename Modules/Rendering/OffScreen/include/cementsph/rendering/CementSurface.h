// The cement's surface from its label map (cement_labels.nrrd of `cementsph inject`: 0 no cement, 1 cement
// in bone, 2 leaked cement outside bone; issue 10, "leakage shown in red on the slices and surface pictures"),
// inside the translucent surface of its vertebra when one is given (vertebraMask):
// the surface of the cement in bone drawn blue and the surface of the leaked cement drawn red, one panel,
// under a title band whose legend says blue = in bone, red = leaked (the red entry only when there is a
// leak, "no leakage" otherwise). Each class's surface is the 0.5 isosurface of its own 0/1 mask WITHOUT
// smoothing, so a leak of a single voxel still shows. Drawn off-screen (makeOffScreenRenderWindow).
//
// The view (so a picture can be read, and tested, against the geometry): parallel projection along
// viewDirection (from the focal point towards the camera) with viewUp; the focal point is the centre of the
// bounding box of the drawn surfaces (both classes: cement voxel centres +- half a voxel, inside the image);
// the parallel scale (half the 3D area's height in mm) is 0.55 x that box's diagonal, so the box fits
// whatever the direction. The 3D area is the
// picture's width and its lower (1 - titleBandFraction) of the height; the title band is above it.
#pragma once

#include <vtkImageData.h>

#include <filesystem>
#include <string>

namespace cementsph::rendering {

struct CementSurfaceOptions {
  int widthPx = 800, heightPx = 720;
  double titleBandFraction = 0.12;
  double viewDirection[3] = {0.55, -1.0, 0.45};
  double viewUp[3] = {0.0, 0.0, 1.0};
  std::string note; // an extra legend line, e.g. "leaked 0.027 ml at 1 site"
  // The vertebra around the cement (issue 20, item 6): a label map on the labels' grid (--labels, or inject's
  // anatomy_labels.nrrd), the voxels equal to vertebraLabel drawn as a translucent bone-coloured surface (the 0.5
  // isosurface of their mask, opacity vertebraOpacity) through which the cement shows. With a vertebra the view
  // frames the vertebra and the cement together (the box is both surfaces').
  vtkImageData* vertebraMask = nullptr;
  int vertebraLabel = 1; // anatomy::TissueClass::TargetVertebra
  double vertebraOpacity = 0.25;
};

// Throws std::invalid_argument if labels is null, not one component, or holds no cement (no voxel 1 or 2);
// std::runtime_error if rendering or writing fails (no file is left).
void writeCementSurface(vtkImageData* labels, const std::filesystem::path& png, const CementSurfaceOptions& options = {});

} // namespace cementsph::rendering
