#include "cementsph/rendering/OffScreenWindow.h"

#include "cementsph/rendering/VirtualDisplay.h"

#include <vtkImageData.h>
#include <vtkPNGWriter.h>
#include <vtkWindowToImageFilter.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <system_error>
#include <unistd.h>

namespace cementsph::rendering {

vtkSmartPointer<vtkRenderWindow> makeOffScreenRenderWindow(int widthPx, int heightPx) {
  if (widthPx < 1 || heightPx < 1 || widthPx > 8192 || heightPx > 8192) {
    throw std::invalid_argument("render window size " + std::to_string(widthPx) + " x " +
                                std::to_string(heightPx) + " px is outside 1..8192");
  }
  VirtualDisplay::ensureDisplay();
  auto window = vtkSmartPointer<vtkRenderWindow>::New();
  // Without the OpenGL factory (vtk_module_autoinit) New() yields a window that silently draws nothing.
  if (!window->IsA("vtkOpenGLRenderWindow")) {
    throw std::runtime_error(std::string("cementsph rendering: VTK made a ") + window->GetClassName() +
                             ", not an OpenGL render window (rendering factories not registered)");
  }
  window->SetOffScreenRendering(1);
  // No multisampling: the pixels should not depend on the GL driver's MSAA, so baselines stay comparable.
  window->SetMultiSamples(0);
  window->SetSize(widthPx, heightPx);
  return window;
}

namespace {

std::filesystem::path temporarySibling(const std::filesystem::path& target) {
  static std::atomic<unsigned> counter{0};
  std::filesystem::path tmp = target.parent_path();
  tmp /= "." + target.filename().string() + ".tmp" + std::to_string(getpid()) + "-" +
         std::to_string(counter++);
  return tmp;
}

} // namespace

void writeWindowPng(vtkRenderWindow* window, const std::filesystem::path& png) {
  if (window == nullptr) throw std::invalid_argument("writeWindowPng: no render window");
  if (png.filename().empty()) throw std::invalid_argument("writeWindowPng: '" + png.string() + "' names no file");
  const std::filesystem::path folder = png.parent_path().empty() ? "." : png.parent_path();
  if (!std::filesystem::is_directory(folder)) {
    throw std::runtime_error("cannot write " + png.string() + ": folder " + folder.string() + " does not exist");
  }

  window->Render();
  auto grab = vtkSmartPointer<vtkWindowToImageFilter>::New();
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  vtkImageData* image = grab->GetOutput();
  int dims[3] = {0, 0, 0};
  image->GetDimensions(dims);
  const int* size = window->GetSize();
  if (dims[0] != size[0] || dims[1] != size[1]) {
    throw std::runtime_error("cementsph rendering: captured " + std::to_string(dims[0]) + " x " +
                             std::to_string(dims[1]) + " px from a " + std::to_string(size[0]) + " x " +
                             std::to_string(size[1]) + " px window");
  }

  writeImagePng(image, png);
}

void writeImagePng(vtkImageData* image, const std::filesystem::path& png) {
  // Write next to the target and rename: readers never see a half-written PNG, and a failure leaves none.
  const std::filesystem::path tmp = temporarySibling(png);
  auto writer = vtkSmartPointer<vtkPNGWriter>::New();
  writer->SetFileName(tmp.string().c_str());
  writer->SetInputData(image);
  writer->Write();
  std::error_code ec;
  if (writer->GetErrorCode() != 0) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error("cementsph rendering: could not write " + png.string());
  }
  std::filesystem::rename(tmp, png, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw std::runtime_error("cementsph rendering: could not move the image into " + png.string() + ": " +
                             ec.message());
  }
}

} // namespace cementsph::rendering
