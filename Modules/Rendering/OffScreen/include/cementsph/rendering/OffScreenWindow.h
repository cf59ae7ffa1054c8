// The one way this module makes a render window, so every picture (plots, isosurfaces, slices) gets
// the same display handling and never reaches VTK's abort on a headless machine.
#pragma once

#include <vtkRenderWindow.h>
#include <vtkSmartPointer.h>

#include <filesystem>

class vtkImageData;

namespace cementsph::rendering {

// An off-screen OpenGL render window of exactly widthPx x heightPx pixels on the first backend that
// works (RenderBackend.h: OSMesa, then surfaceless EGL, then an X display, starting Xvfb if need be).
// Throws std::invalid_argument for sizes outside 1..8192, RenderFailure if no backend works.
vtkSmartPointer<vtkRenderWindow> makeOffScreenRenderWindow(int widthPx, int heightPx);

// Renders `window` and writes its colour buffer (RGB) to `png` atomically: the image goes to a temporary
// file in the same folder which is then renamed into place, so a failure never leaves a partial file.
// Throws RenderFailure if VTK reported an error while rendering, if the picture is all black (every
// picture of ours has a light background, so black means a context that drew nothing) or if the captured
// image is not the window's size; std::runtime_error if the file cannot be written.
void writeWindowPng(vtkRenderWindow* window, const std::filesystem::path& png);

// True if every byte of the image's scalars is 0 (or it has none).
bool isAllBlack(vtkImageData* image);

// Names the backend on stderr when the first window is made (the programs' --verbose).
void setVerboseRendering(bool verbose);

// Writes an image (e.g. one composed without GL) to `png` the same atomic way.
void writeImagePng(vtkImageData* image, const std::filesystem::path& png);

} // namespace cementsph::rendering
