// Which OpenGL drives the off-screen pictures, and the error a failed picture raises.
//
// Debian's VTK 9.1 is built for GLX only, yet Mesa's OSMesa and surfaceless EGL both drive it through
// vtkGenericOpenGLRenderWindow with no X server at all (shared/reference/offscreen-notes.md). The order
// tried for every window: OSMesa (when the build found libOSMesa), then surfaceless EGL, and only if both
// fail an X display (DISPLAY, or a private Xvfb started by VirtualDisplay).
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

namespace cementsph::rendering {

enum class RenderBackend { OSMesa, SurfacelessEGL, XDisplay };

// "osmesa", "egl", "x": the names CEMENTSPH_RENDER_BACKEND takes and metrics/log lines report.
std::string renderBackendName(RenderBackend backend);

// Checks CEMENTSPH_RENDER_BACKEND at a program's start, so that a misspelt value is one line before any work
// rather than a failed picture at the end: std::invalid_argument naming the variable and the valid values.
void checkRenderBackendEnvironment();

// The backend that made the most recent render window in this process; empty before the first one.
std::optional<RenderBackend> lastRenderBackend();

// A picture that could not be drawn: no GL context, a GL/VTK error during the render, or an image that
// came back all black (the silent failure mode of a half-initialised context). Programs exit with
// status 3 ("failed picture") on it, never writing the picture.
class RenderFailure : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
  static constexpr int exitCode = 3;
};

} // namespace cementsph::rendering
