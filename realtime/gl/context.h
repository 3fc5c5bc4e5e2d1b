// A headless OpenGL context for the GL twin of the real-time renderer (issue 15): OpenGL 4.5 core
// (the passes' GLSL asks for 3.30) through OSMesa or EGL, with no window system. One layer for
// every platform, one loader (glad2, generated at build time; `realtime/gl/CMakeLists.txt`):
//
//   - OSMesa: `OSMesaCreateContextAttribs` with the core profile, made current on a 1 x 1
//     buffer (the passes draw into their own framebuffer objects). Mesa's llvmpipe.
//   - EGL: the device platform (`EGL_EXT_device_enumeration`) with a hardware device first (what
//     a machine with a GPU offers, no X server needed), else Mesa's surfaceless platform
//     (`EGL_PLATFORM_SURFACELESS_MESA`); `EGL_OPENGL_API`, no surface (surfaceless make-current).
//
// `GlPlatform::kAuto` tries EGL with a hardware device, then OSMesa, then EGL surfaceless. A
// context is made current on the calling thread when created and by `make_current`; glad's
// function pointers are process-wide, so `make_current` reloads them when another context was
// current (a test may hold an OSMesa and an EGL context). Contexts are not thread-safe: one
// thread at a time.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace ssslab::realtime::gl {

enum class GlPlatform {
    kAuto,    ///< EGL device (a GPU), else OSMesa, else EGL surfaceless
    kOsmesa,  ///< Mesa's off-screen library (llvmpipe)
    kEgl,     ///< EGL: a hardware device if there is one, else Mesa's surfaceless platform
};

const char* to_string(GlPlatform p);
/// "auto", "osmesa" or "egl"; throws std::invalid_argument naming the choices otherwise.
GlPlatform parse_gl_platform(const std::string& s);

/// The platforms this build was compiled with ("osmesa", "egl"); empty without the GL twin.
std::vector<std::string> gl_platforms_built();

class GlContext;
std::unique_ptr<GlContext> try_gl_context(GlPlatform platform, std::string& why);

class GlContext {
  public:
    /// A context of the platform, current on this thread. Throws std::runtime_error saying why
    /// none could be made (platform not built in, no display, no core 3.3 context, loader).
    static std::unique_ptr<GlContext> create(GlPlatform platform = GlPlatform::kAuto);
    ~GlContext();
    GlContext(const GlContext&) = delete;
    GlContext& operator=(const GlContext&) = delete;

    void make_current();
    /// "osmesa", "egl-device" or "egl-surfaceless".
    const std::string& platform() const { return platform_; }
    /// GL_RENDERER and GL_VERSION, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)", "4.5 (Core Profile)
    /// Mesa 22.3.6".
    const std::string& renderer() const { return renderer_; }
    const std::string& version() const { return version_; }

    struct Impl;  ///< the platform's handles (context.cpp)

  private:
    GlContext() = default;
    friend std::unique_ptr<GlContext> try_gl_context(GlPlatform, std::string&);
    std::unique_ptr<Impl> impl_;
    std::string platform_, renderer_, version_;
};

/// A context, or null with the reason in `why` (for tests that skip when no platform works).
std::unique_ptr<GlContext> try_gl_context(GlPlatform platform, std::string& why);

}  // namespace ssslab::realtime::gl
