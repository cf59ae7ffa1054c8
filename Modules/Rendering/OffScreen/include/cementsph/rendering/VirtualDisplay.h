// An X display for VTK on machines that have none: the last of the rendering backends (RenderBackend.h),
// used only when neither OSMesa nor surfaceless EGL gives a context, or when CEMENTSPH_RENDER_BACKEND=x.
//
// An X render window without a reachable X display aborts the whole process, so the X backend calls
// ensureDisplay() before it makes one. If DISPLAY names a server we can connect to, it does nothing;
// otherwise it starts a private Xvfb (Mesa llvmpipe does the drawing), points DISPLAY at it, and stops it
// when the program exits.
#pragma once

#include <string>

namespace cementsph::rendering {

class VirtualDisplay {
public:
  // Idempotent and thread-safe; cheap after the first call. Xvfb is started at most once per process, and
  // if DISPLAY was unset or changed since, it is pointed back at the display settled on. Throws
  // std::runtime_error (one line) if no display can be had, e.g. when Xvfb is not installed; a failed
  // attempt is retried by the next call.
  // Note: it may setenv("DISPLAY"); other threads must not read the environment at that moment.
  static void ensureDisplay();

  // The DISPLAY string currently in use, after ensureDisplay().
  static std::string displayName();

  // True if this process started its own Xvfb.
  static bool startedVirtualServer();
};

} // namespace cementsph::rendering
