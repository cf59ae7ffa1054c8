#include "ContextWindow.h"

#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkGenericOpenGLRenderWindow.h>

#define EGL_EGLEXT_PROTOTYPES
#include <EGL/egl.h>
#include <EGL/eglext.h>

#ifdef CEMENTSPH_HAVE_OSMESA
#include <GL/osmesa.h>
#else
#include <GL/gl.h>
#endif

#include <dlfcn.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

namespace cementsph::rendering::detail {
namespace {

// Which context the GLEW hooks below serve. GLEW keeps one global table of GL entry points, so a process
// sticks to one backend once a window worked (OffScreenWindow.cpp settles it).
enum class GlewRoute { Glx, OSMesa, Egl };
std::atomic<GlewRoute> gGlewRoute{GlewRoute::Glx};

using GenericFunction = void (*)();

GenericFunction realGlxGetProcAddress(const unsigned char* name) {
  using Lookup = GenericFunction (*)(const unsigned char*);
  static const auto real = reinterpret_cast<Lookup>(dlsym(RTLD_NEXT, "glXGetProcAddressARB"));
  return real != nullptr ? real(name) : nullptr;
}

} // namespace
} // namespace cementsph::rendering::detail

// The two GLEW hooks (offscreen-notes.md). Debian's libGLEW is the GLX flavour: it looks every GL entry
// point up with glXGetProcAddressARB and ends glewInit() with glxewInit(), which fails without a GLX
// display. Both go through libGLEW's symbol table, so these definitions, exported from the program
// (CMakeLists: --export-dynamic-symbol), take their place. On the X fallback they forward to the real ones.
extern "C" {

__attribute__((visibility("default"))) void (*glXGetProcAddressARB(const unsigned char* name))() {
  using namespace cementsph::rendering::detail;
  const bool glxName = std::strncmp(reinterpret_cast<const char*>(name), "glX", 3) == 0;
#ifdef CEMENTSPH_HAVE_OSMESA
  if (!glxName && gGlewRoute.load() == GlewRoute::OSMesa) {
    return OSMesaGetProcAddress(reinterpret_cast<const char*>(name));
  }
#endif
  if (!glxName && gGlewRoute.load() == GlewRoute::Egl) {
    return eglGetProcAddress(reinterpret_cast<const char*>(name));
  }
  return realGlxGetProcAddress(name);
}

__attribute__((visibility("default"))) unsigned int glxewInit() {
  using namespace cementsph::rendering::detail;
  if (gGlewRoute.load() != GlewRoute::Glx) return 0; // GLEW_OK: there is no GLX to initialise
  using Init = unsigned int (*)();
  static const auto real = reinterpret_cast<Init>(dlsym(RTLD_NEXT, "glxewInit"));
  return real != nullptr ? real() : 1;
}

} // extern "C"

namespace cementsph::rendering::detail {
namespace {

// The context behind one window: made current on VTK's WindowMakeCurrentEvent, destroyed with the window.
class Context {
public:
  virtual ~Context() = default;
  virtual bool makeCurrent(int widthPx, int heightPx) = 0;
};

#ifdef CEMENTSPH_HAVE_OSMESA
class OSMesaWindowContext final : public Context {
public:
  explicit OSMesaWindowContext(OSMesaContext context) : context_(context) {}
  ~OSMesaWindowContext() override { OSMesaDestroyContext(context_); }
  bool makeCurrent(int widthPx, int heightPx) override {
    // The colour buffer follows the window if a caller resizes it after creation.
    const std::size_t bytes = static_cast<std::size_t>(widthPx) * static_cast<std::size_t>(heightPx) * 4;
    if (buffer_.size() != bytes) buffer_.assign(bytes, 0);
    return OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, widthPx, heightPx) == GL_TRUE;
  }

private:
  OSMesaContext context_;
  std::vector<unsigned char> buffer_;
};

std::unique_ptr<Context> makeOSMesaContext(std::string& whyNot) {
  const int attributes[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_STENCIL_BITS, 8,
                            OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                            OSMESA_CONTEXT_MINOR_VERSION, 2, 0};
  OSMesaContext context = OSMesaCreateContextAttribs(attributes, nullptr);
  if (context == nullptr) {
    whyNot = "OSMesa could not create an OpenGL 3.2 core context";
    return nullptr;
  }
  return std::make_unique<OSMesaWindowContext>(context);
}
#endif

class EglWindowContext final : public Context {
public:
  EglWindowContext(EGLDisplay display, EGLContext context) : display_(display), context_(context) {}
  ~EglWindowContext() override {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
  }
  // No surface at all: VTK draws into its own framebuffer object and the picture is read from there.
  bool makeCurrent(int, int) override {
    return eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) == EGL_TRUE;
  }

private:
  EGLDisplay display_;
  EGLContext context_;
};

// The surfaceless display, initialised once per process (EGL displays are process-wide anyway).
EGLDisplay surfacelessDisplay(std::string& whyNot) {
  static EGLDisplay display = EGL_NO_DISPLAY;
  static std::string failure;
  static bool tried = false;
  if (!tried) {
    tried = true;
    // Pictures are compared with software-rendered baselines; a GPU driver would anti-alias and round
    // differently. Mesa honours this for surfaceless EGL; a user's own setting wins.
    setenv("LIBGL_ALWAYS_SOFTWARE", "1", 0);
    const auto getPlatformDisplay =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (getPlatformDisplay == nullptr) {
      failure = "EGL has no eglGetPlatformDisplayEXT";
    } else {
      display = getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      EGLint major = 0, minor = 0;
      if (display == EGL_NO_DISPLAY || eglInitialize(display, &major, &minor) != EGL_TRUE) {
        failure = "EGL has no surfaceless Mesa display";
        display = EGL_NO_DISPLAY;
      } else if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {
        failure = "EGL cannot bind desktop OpenGL";
        display = EGL_NO_DISPLAY;
      }
    }
  }
  whyNot = failure;
  return display;
}

std::unique_ptr<Context> makeEglContext(std::string& whyNot) {
  EGLDisplay display = surfacelessDisplay(whyNot);
  if (display == EGL_NO_DISPLAY) return nullptr;
  // EGL_SURFACE_TYPE defaults to windows, which a surfaceless display has none of.
  const EGLint configAttributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                     EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_ALPHA_SIZE, 8,
                                     EGL_DEPTH_SIZE, 24, EGL_STENCIL_SIZE, 8, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (eglChooseConfig(display, configAttributes, &config, 1, &count) != EGL_TRUE || count < 1) {
    whyNot = "EGL offers no RGBA8 / depth 24 / stencil 8 OpenGL configuration";
    return nullptr;
  }
  const EGLint contextAttributes[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 2,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                      EGL_NONE};
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, contextAttributes);
  if (context == EGL_NO_CONTEXT) {
    whyNot = "EGL could not create an OpenGL 3.2 core context";
    return nullptr;
  }
  return std::make_unique<EglWindowContext>(display, context);
}

// A context that answers glGetString with 3.2 or newer is one VTK can use; a NULL answer is the sign of
// GL calls reaching another library than the context's (the link-order trap of offscreen-notes.md).
bool contextAnswers(std::string& whyNot) {
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  if (version == nullptr) {
    whyNot = "the context is current but glGetString(GL_VERSION) returns nothing";
    return false;
  }
  int major = 0, minor = 0;
  if (std::sscanf(version, "%d.%d", &major, &minor) != 2 || major * 10 + minor < 32) {
    whyNot = std::string("the context offers OpenGL ") + version + ", VTK needs 3.2";
    return false;
  }
  return true;
}

void onMakeCurrent(vtkObject* caller, unsigned long, void* clientData, void*) {
  auto* window = static_cast<vtkRenderWindow*>(caller);
  const int* size = window->GetSize();
  static_cast<Context*>(clientData)->makeCurrent(size[0], size[1]);
}

void deleteContext(void* clientData) { delete static_cast<Context*>(clientData); }

} // namespace

bool backendCompiledIn(RenderBackend backend) {
#ifndef CEMENTSPH_HAVE_OSMESA
  if (backend == RenderBackend::OSMesa) return false;
#endif
  (void)backend;
  return true;
}

void useGlxForGlew() { gGlewRoute.store(GlewRoute::Glx); }

vtkSmartPointer<vtkRenderWindow> makeContextWindow(RenderBackend backend, int widthPx, int heightPx,
                                                   std::string& whyNot) {
  std::unique_ptr<Context> context;
  GlewRoute route = GlewRoute::Glx;
  if (backend == RenderBackend::OSMesa) {
#ifdef CEMENTSPH_HAVE_OSMESA
    context = makeOSMesaContext(whyNot);
    route = GlewRoute::OSMesa;
#else
    whyNot = "this build has no OSMesa (libosmesa6-dev was missing when it was configured)";
#endif
  } else if (backend == RenderBackend::SurfacelessEGL) {
    context = makeEglContext(whyNot);
    route = GlewRoute::Egl;
  } else {
    whyNot = "not a context backend";
  }
  if (!context) return nullptr;
  if (!context->makeCurrent(widthPx, heightPx)) {
    whyNot = renderBackendName(backend) + " could not make its context current";
    return nullptr;
  }
  if (!contextAnswers(whyNot)) return nullptr;
  gGlewRoute.store(route);

  auto window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
  window->SetSize(widthPx, heightPx);
  window->SetMultiSamples(0);
  window->SetIsDirect(1);
  window->SetSupportsOpenGL(1);
  window->SetIsCurrent(true);
  window->SetReadyForRendering(true);
  window->SetMapped(1);
  // OSMesa has a default framebuffer (its buffer) to blit the finished frame into; surfaceless EGL has
  // none, and the picture is read from VTK's own framebuffer.
  if (backend == RenderBackend::OSMesa) window->SetFrameBlitModeToBlitToCurrent();
  else window->SetFrameBlitModeToNoBlit();

  auto makeCurrent = vtkSmartPointer<vtkCallbackCommand>::New();
  makeCurrent->SetCallback(onMakeCurrent);
  makeCurrent->SetClientData(context.release());
  // The command (and with it the context) lives as long as the window's observer list, i.e. until after
  // the window's own destructor has released its GL resources on that context.
  makeCurrent->SetClientDataDeleteCallback(deleteContext);
  window->AddObserver(vtkCommand::WindowMakeCurrentEvent, makeCurrent);
  return window;
}

} // namespace cementsph::rendering::detail
