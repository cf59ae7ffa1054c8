#include "cementsph/rendering/OffScreenWindow.h"

#include "ContextWindow.h"
#include "cementsph/rendering/RenderBackend.h"
#include "cementsph/rendering/VirtualDisplay.h"

#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkImageData.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <atomic>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>
#include <unistd.h>
#include <vector>

namespace cementsph::rendering {

std::string renderBackendName(RenderBackend backend) {
  switch (backend) {
  case RenderBackend::OSMesa: return "osmesa";
  case RenderBackend::SurfacelessEGL: return "egl";
  case RenderBackend::XDisplay: return "x";
  }
  return "unknown";
}

namespace {

std::mutex gBackendMutex;
// The backend that worked first; later windows use it only (GLEW's entry-point table is process-wide).
std::optional<RenderBackend> gSettledBackend;
// --verbose: one line naming the backend when the first window is made. CEMENTSPH_VERBOSE=1 does the same
// for programs that have no such option.
std::atomic<bool> gVerbose{std::getenv("CEMENTSPH_VERBOSE") != nullptr};

// CEMENTSPH_RENDER_BACKEND=osmesa|egl|x forces one backend, with no fallback (tests of each path, and
// a user's escape hatch); unset means the order OSMesa, EGL, X.
std::vector<RenderBackend> backendsToTry() {
  const char* forced = std::getenv("CEMENTSPH_RENDER_BACKEND");
  if (forced == nullptr || *forced == '\0') {
    return {RenderBackend::OSMesa, RenderBackend::SurfacelessEGL, RenderBackend::XDisplay};
  }
  for (RenderBackend b : {RenderBackend::OSMesa, RenderBackend::SurfacelessEGL, RenderBackend::XDisplay}) {
    if (renderBackendName(b) == forced) return {b};
  }
  throw RenderFailure(std::string("CEMENTSPH_RENDER_BACKEND is '") + forced +
                      "'; use osmesa, egl or x, or unset it to let the program choose");
}

} // namespace

void checkRenderBackendEnvironment() {
  try {
    backendsToTry();
  } catch (const RenderFailure& e) {
    throw std::invalid_argument(e.what());
  }
}

namespace {

vtkSmartPointer<vtkRenderWindow> makeXWindow() {
  detail::useGlxForGlew();
  VirtualDisplay::ensureDisplay();
  auto window = vtkSmartPointer<vtkRenderWindow>::New();
  // Without the OpenGL factory (vtk_module_autoinit) New() yields a window that silently draws nothing.
  if (!window->IsA("vtkOpenGLRenderWindow")) {
    throw RenderFailure(std::string("cementsph rendering: VTK made a ") + window->GetClassName() +
                        ", not an OpenGL render window (rendering factories not registered)");
  }
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);
  return window;
}

vtkSmartPointer<vtkRenderWindow> makeWindowOn(RenderBackend backend, int widthPx, int heightPx,
                                              std::string& whyNot) {
  if (backend != RenderBackend::XDisplay) {
    return detail::makeContextWindow(backend, widthPx, heightPx, whyNot);
  }
  try {
    return makeXWindow();
  } catch (const std::exception& e) {
    whyNot = e.what();
    return nullptr;
  }
}

} // namespace

void setVerboseRendering(bool verbose) { gVerbose.store(verbose); }

std::optional<RenderBackend> lastRenderBackend() {
  std::lock_guard<std::mutex> lock(gBackendMutex);
  return gSettledBackend;
}

vtkSmartPointer<vtkRenderWindow> makeOffScreenRenderWindow(int widthPx, int heightPx) {
  if (widthPx < 1 || heightPx < 1 || widthPx > 8192 || heightPx > 8192) {
    throw std::invalid_argument("render window size " + std::to_string(widthPx) + " x " +
                                std::to_string(heightPx) + " px is outside 1..8192");
  }
  std::lock_guard<std::mutex> lock(gBackendMutex);
  const std::vector<RenderBackend> candidates =
      gSettledBackend ? std::vector<RenderBackend>{*gSettledBackend} : backendsToTry();
  std::string reasons;
  for (RenderBackend backend : candidates) {
    std::string whyNot;
    auto window = makeWindowOn(backend, widthPx, heightPx, whyNot);
    if (window) {
      // No multisampling: the pixels should not depend on the GL driver's MSAA, so baselines compare.
      window->SetSize(widthPx, heightPx);
      if (!gSettledBackend && gVerbose.load()) {
        std::cerr << "cementsph rendering: pictures are drawn with " << renderBackendName(backend) << "\n";
      }
      gSettledBackend = backend;
      return window;
    }
    if (!detail::backendCompiledIn(backend) && candidates.size() > 1) continue; // not a failure, just absent
    reasons += (reasons.empty() ? "" : "; ") + renderBackendName(backend) + ": " + whyNot;
  }
  throw RenderFailure("cementsph rendering: no OpenGL to draw pictures with (" + reasons +
                      "); install libosmesa6 or Mesa's libegl-mesa0, or use --no-pictures");
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

bool isAllBlack(vtkImageData* image) {
  auto* pixels = vtkUnsignedCharArray::SafeDownCast(image->GetPointData()->GetScalars());
  if (pixels == nullptr) return true;
  const unsigned char* first = pixels->GetPointer(0);
  const vtkIdType count = pixels->GetNumberOfValues();
  for (vtkIdType i = 0; i < count; ++i) {
    if (first[i] != 0) return false;
  }
  return true;
}

void writeWindowPng(vtkRenderWindow* window, const std::filesystem::path& png) {
  if (window == nullptr) throw std::invalid_argument("writeWindowPng: no render window");
  if (png.filename().empty()) throw std::invalid_argument("writeWindowPng: '" + png.string() + "' names no file");
  const std::filesystem::path folder = png.parent_path().empty() ? "." : png.parent_path();
  if (!std::filesystem::is_directory(folder)) {
    throw std::runtime_error("cannot write " + png.string() + ": folder " + folder.string() + " does not exist");
  }

  // VTK reports a context it cannot use (GLEW, shaders, framebuffers) as errors on the window and then
  // draws nothing; collect them so that the picture fails instead.
  std::string glErrors;
  auto onError = vtkSmartPointer<vtkCallbackCommand>::New();
  onError->SetClientData(&glErrors);
  onError->SetCallback([](vtkObject*, unsigned long, void* clientData, void* callData) {
    auto* errors = static_cast<std::string*>(clientData);
    if (errors->empty() && callData != nullptr) *errors = static_cast<const char*>(callData);
  });
  const unsigned long observer = window->AddObserver(vtkCommand::ErrorEvent, onError);
  window->Render();
  auto grab = vtkSmartPointer<vtkWindowToImageFilter>::New();
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  window->RemoveObserver(observer);
  vtkImageData* image = grab->GetOutput();
  int dims[3] = {0, 0, 0};
  image->GetDimensions(dims);
  const int* size = window->GetSize();
  if (dims[0] != size[0] || dims[1] != size[1]) {
    throw RenderFailure("cementsph rendering: captured " + std::to_string(dims[0]) + " x " +
                        std::to_string(dims[1]) + " px from a " + std::to_string(size[0]) + " x " +
                        std::to_string(size[1]) + " px window");
  }
  const std::optional<RenderBackend> used = lastRenderBackend();
  const std::string backend = used ? renderBackendName(*used) : "unknown";
  if (!glErrors.empty()) {
    std::string firstLine = glErrors.substr(0, glErrors.find('\n'));
    throw RenderFailure("cementsph rendering: failed picture " + png.string() + " (" + backend +
                        "): " + firstLine);
  }
  if (isAllBlack(image)) {
    throw RenderFailure("cementsph rendering: failed picture " + png.string() + " (" + backend +
                        "): the render came back all black, the sign of a GL context that draws "
                        "nothing; try CEMENTSPH_RENDER_BACKEND=egl or x");
  }

  writeImagePng(image, png);
}

void writeImagePng(vtkImageData* image, const std::filesystem::path& png) {
  // Write next to the target and rename: readers never see a half-written PNG, and a failure leaves none.
  // A folder that is not there is said before VTK's PNG writer runs: VTK 9.1's writer, failing to open its file,
  // returns without freeing the libpng structures it made (LeakSanitizer, XrayFramesPicture.BadInput...).
  const std::filesystem::path folder = png.has_parent_path() ? png.parent_path() : std::filesystem::path(".");
  std::error_code folderError;
  if (!std::filesystem::is_directory(folder, folderError))
    throw std::runtime_error("cementsph rendering: could not write " + png.string() + ": the folder " +
                             folder.string() + " does not exist");
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
