// The one way this module makes a render window, so every picture (plots, isosurfaces, slices) gets
// the same display handling and never reaches VTK's abort on a headless machine.
#pragma once

#include <vtkRenderWindow.h>
#include <vtkSmartPointer.h>

#include <filesystem>

class vtkImageData;

namespace cementsph::rendering {

// Calls VirtualDisplay::ensureDisplay(), then returns an off-screen OpenGL render window of exactly
// widthPx x heightPx pixels. Throws std::invalid_argument for sizes outside 1..8192.
vtkSmartPointer<vtkRenderWindow> makeOffScreenRenderWindow(int widthPx, int heightPx);

// Renders `window` and writes its colour buffer (RGB) to `png` atomically: the image goes to a temporary
// file in the same folder which is then renamed into place, so a failure never leaves a partial file.
// Throws std::runtime_error if the captured image is not the window's size or the file cannot be written.
void writeWindowPng(vtkRenderWindow* window, const std::filesystem::path& png);

// Writes an image (e.g. one composed without GL) to `png` the same atomic way.
void writeImagePng(vtkImageData* image, const std::filesystem::path& png);

} // namespace cementsph::rendering
