#include "realtime/gl/context.h"

// glad first: it stands in for GL/gl.h, which the platform headers would otherwise include.
#include <glad/gl.h>
#ifdef SSSLAB_GL_OSMESA
#include <GL/osmesa.h>
#endif
#ifdef SSSLAB_GL_EGL
#include <EGL/egl.h>
#include <EGL/eglext.h>
#endif

#include <cstring>
#include <stdexcept>

namespace ssslab::realtime::gl {

namespace {

// The context glad's function pointers were last loaded for (they are process-wide).
const void* g_loaded_for = nullptr;

}  // namespace

const char* to_string(GlPlatform p) {
    switch (p) {
        case GlPlatform::kOsmesa:
            return "osmesa";
        case GlPlatform::kEgl:
            return "egl";
        case GlPlatform::kAuto:
            break;
    }
    return "auto";
}

GlPlatform parse_gl_platform(const std::string& s) {
    if (s == "auto") return GlPlatform::kAuto;
    if (s == "osmesa") return GlPlatform::kOsmesa;
    if (s == "egl") return GlPlatform::kEgl;
    throw std::invalid_argument("unknown GL platform '" + s + "' (choices: auto, osmesa, egl)");
}

std::vector<std::string> gl_platforms_built() {
    std::vector<std::string> v;
#ifdef SSSLAB_GL_OSMESA
    v.push_back("osmesa");
#endif
#ifdef SSSLAB_GL_EGL
    v.push_back("egl");
#endif
    return v;
}

struct GlContext::Impl {
#ifdef SSSLAB_GL_OSMESA
    OSMesaContext osmesa = nullptr;
    unsigned char pixel[4] = {0, 0, 0, 0};  // the 1 x 1 buffer OSMesa is made current on
#endif
#ifdef SSSLAB_GL_EGL
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext egl = EGL_NO_CONTEXT;
#endif
    bool is_osmesa = false;

    void make_current() const {
#ifdef SSSLAB_GL_OSMESA
        if (is_osmesa) {
            if (!OSMesaMakeCurrent(osmesa, const_cast<unsigned char*>(pixel), GL_UNSIGNED_BYTE, 1,
                                   1))
                throw std::runtime_error("OSMesaMakeCurrent failed");
            return;
        }
#endif
#ifdef SSSLAB_GL_EGL
        if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, egl))
            throw std::runtime_error("eglMakeCurrent (surfaceless) failed");
#endif
    }
    void load() const {
        int version = 0;
#ifdef SSSLAB_GL_OSMESA
        if (is_osmesa) version = gladLoadGL(reinterpret_cast<GLADloadfunc>(OSMesaGetProcAddress));
#endif
#ifdef SSSLAB_GL_EGL
        if (!is_osmesa) version = gladLoadGL(reinterpret_cast<GLADloadfunc>(eglGetProcAddress));
#endif
        if (version == 0) throw std::runtime_error("the GL loader (glad) found no OpenGL");
        if (GLAD_VERSION_MAJOR(version) * 10 + GLAD_VERSION_MINOR(version) < 33)
            throw std::runtime_error("OpenGL " + std::to_string(GLAD_VERSION_MAJOR(version)) + "." +
                                     std::to_string(GLAD_VERSION_MINOR(version)) +
                                     ": the GL twin needs 3.3 core");
    }
    ~Impl() {
#ifdef SSSLAB_GL_OSMESA
        if (osmesa) OSMesaDestroyContext(osmesa);
#endif
#ifdef SSSLAB_GL_EGL
        if (egl != EGL_NO_CONTEXT) {
            if (eglGetCurrentContext() == egl)
                eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            eglDestroyContext(display, egl);
        }
        // The display is not terminated: EGL displays are per process and per device, and
        // terminating one would end every other context on it.
#endif
    }
};

namespace {

#ifdef SSSLAB_GL_OSMESA
std::unique_ptr<GlContext::Impl> make_osmesa(std::string& why) {
    const int attribs[] = {OSMESA_FORMAT,
                           OSMESA_RGBA,
                           OSMESA_DEPTH_BITS,
                           0,
                           OSMESA_STENCIL_BITS,
                           0,
                           OSMESA_ACCUM_BITS,
                           0,
                           OSMESA_PROFILE,
                           OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION,
                           3,
                           OSMESA_CONTEXT_MINOR_VERSION,
                           3,
                           0};
    auto impl = std::make_unique<GlContext::Impl>();
    impl->is_osmesa = true;
    impl->osmesa = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!impl->osmesa) {
        why = "OSMesaCreateContextAttribs gave no OpenGL 3.3 core context";
        return nullptr;
    }
    return impl;
}
#endif

#ifdef SSSLAB_GL_EGL
// An OpenGL 3.3 core context on an initialised display, or null (why says what failed).
std::unique_ptr<GlContext::Impl> make_egl_on(EGLDisplay display, std::string& why) {
    if (display == EGL_NO_DISPLAY) {
        why = "no EGL display";
        return nullptr;
    }
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor)) {
        why = "eglInitialize failed";
        return nullptr;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        why = "eglBindAPI(EGL_OPENGL_API) failed";
        return nullptr;
    }
    // No surface type asked for (the default, EGL_WINDOW_BIT, has no config without a window
    // system).
    const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, 0,
                                     EGL_NONE};
    EGLConfig config = nullptr;
    EGLint n = 0;
    if (!eglChooseConfig(display, config_attribs, &config, 1, &n) || n < 1) {
        why = "no EGL config renders OpenGL";
        return nullptr;
    }
    const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                  3,
                                  EGL_CONTEXT_MINOR_VERSION,
                                  3,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                  EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                  EGL_NONE};
    auto impl = std::make_unique<GlContext::Impl>();
    impl->display = display;
    impl->egl = eglCreateContext(display, config, EGL_NO_CONTEXT, ctx_attribs);
    if (impl->egl == EGL_NO_CONTEXT) {
        why = "eglCreateContext gave no OpenGL 3.3 core context";
        return nullptr;
    }
    return impl;
}

// EGL's device platform with a hardware device (skipping Mesa's software device), or null.
std::unique_ptr<GlContext::Impl> make_egl_device(std::string& why) {
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!client || !std::strstr(client, "EGL_EXT_device_enumeration") ||
        !std::strstr(client, "EGL_EXT_platform_device")) {
        why = "EGL has no device enumeration";
        return nullptr;
    }
    auto query_devices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        eglGetProcAddress("eglQueryDeviceStringEXT"));
    auto platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!query_devices || !device_string || !platform_display) {
        why = "EGL's device functions are missing";
        return nullptr;
    }
    EGLDeviceEXT devices[16];
    EGLint count = 0;
    if (!query_devices(16, devices, &count) || count < 1) {
        why = "EGL lists no device";
        return nullptr;
    }
    why = "EGL lists only software devices";
    for (EGLint i = 0; i < count; ++i) {
        const char* ext = device_string(devices[i], EGL_EXTENSIONS);
        if (ext && std::strstr(ext, "EGL_MESA_device_software")) continue;
        auto impl =
            make_egl_on(platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr), why);
        if (impl) return impl;
    }
    return nullptr;
}

// Mesa's surfaceless platform (llvmpipe without a GPU), or null.
std::unique_ptr<GlContext::Impl> make_egl_surfaceless(std::string& why) {
    auto platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!platform_display) {
        why = "eglGetPlatformDisplayEXT is missing";
        return nullptr;
    }
    return make_egl_on(
        platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr), why);
}
#endif

}  // namespace

std::unique_ptr<GlContext> GlContext::create(GlPlatform platform) {
    std::string why;
    std::unique_ptr<GlContext> c = try_gl_context(platform, why);
    if (!c) throw std::runtime_error(why);
    return c;
}

std::unique_ptr<GlContext> try_gl_context(GlPlatform platform, std::string& why) {
    std::unique_ptr<GlContext::Impl> impl;
    std::string name;
    std::string reasons;
    auto note = [&](const char* what, const std::string& w) {
        reasons += (reasons.empty() ? "" : "; ") + std::string(what) + ": " + w;
    };
    [[maybe_unused]] const bool want_egl =
        platform == GlPlatform::kEgl || platform == GlPlatform::kAuto;
    [[maybe_unused]] const bool want_osmesa =
        platform == GlPlatform::kOsmesa || platform == GlPlatform::kAuto;
#ifdef SSSLAB_GL_EGL
    if (!impl && want_egl) {
        std::string w;
        impl = make_egl_device(w);
        if (impl)
            name = "egl-device";
        else
            note("egl-device", w);
    }
#endif
#ifdef SSSLAB_GL_OSMESA
    if (!impl && want_osmesa) {
        std::string w;
        impl = make_osmesa(w);
        if (impl)
            name = "osmesa";
        else
            note("osmesa", w);
    }
#endif
#ifdef SSSLAB_GL_EGL
    if (!impl && want_egl) {
        std::string w;
        impl = make_egl_surfaceless(w);
        if (impl)
            name = "egl-surfaceless";
        else
            note("egl-surfaceless", w);
    }
#endif
    if (!impl) {
        why = reasons.empty()
                  ? std::string("this build has no GL platform '") + to_string(platform) + "'"
                  : "no OpenGL context (" + reasons + ")";
        return nullptr;
    }
    std::unique_ptr<GlContext> c(new GlContext());
    c->impl_ = std::move(impl);
    c->platform_ = name;
    try {
        c->make_current();
    } catch (const std::exception& e) {
        why = name + ": " + e.what();
        return nullptr;
    }
    auto str = [](GLenum e) {
        const GLubyte* s = glGetString(e);
        return s ? std::string(reinterpret_cast<const char*>(s)) : std::string();
    };
    c->renderer_ = str(GL_RENDERER);
    c->version_ = str(GL_VERSION);
    return c;
}

GlContext::~GlContext() {
    if (g_loaded_for == this) g_loaded_for = nullptr;
}

void GlContext::make_current() {
    impl_->make_current();
    if (g_loaded_for != this) {
        impl_->load();
        g_loaded_for = this;
    }
}

}  // namespace ssslab::realtime::gl
