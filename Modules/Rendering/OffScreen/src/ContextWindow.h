// Render windows on an OpenGL context this library makes itself (OSMesa or surfaceless EGL), without
// an X server. Private to the Rendering module; OffScreenWindow.cpp picks the backend.
#pragma once

#include "cementsph/rendering/RenderBackend.h"

#include <vtkRenderWindow.h>
#include <vtkSmartPointer.h>

#include <string>

namespace cementsph::rendering::detail {

// True if this build can try `backend` at all (OSMesa needs libOSMesa found at configure time).
bool backendCompiledIn(RenderBackend backend);

// A vtkGenericOpenGLRenderWindow of widthPx x heightPx on a fresh OSMesa or EGL context, with the
// context checked (GL 3.2 or newer answers glGetString). On failure returns null and says why in
// `whyNot`. Also points the GLEW hooks (GLHooks in ContextWindow.cpp) at `backend`.
vtkSmartPointer<vtkRenderWindow> makeContextWindow(RenderBackend backend, int widthPx, int heightPx,
                                                   std::string& whyNot);

// Routes the GLEW hooks to the real GLX functions again (the X display fallback).
void useGlxForGlew();

} // namespace cementsph::rendering::detail
