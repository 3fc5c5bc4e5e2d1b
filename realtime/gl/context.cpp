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

#include <dlfcn.h>

#include <cstring>
#include <stdexcept>

namespace ssslab::realtime::gl {

namespace {

// The context glad's function pointers were last loaded for (they are process-wide).
const void* g_loaded_for = nullptr;

// The platform libraries are opened when a context is first asked for, not linked: linked, they
// loaded libOSMesa and LLVM (50 MB, 0.1-0.2 s) into every run of ssslab, GL or not.
void* open_first(std::initializer_list<const char*> names, std::string& error) {
    for (const char* n : names)
        if (void* h = dlopen(n, RTLD_NOW | RTLD_LOCAL)) return h;
    error = std::string("cannot open ") + *names.begin() + " (" + dlerror() + ")";
    return nullptr;
}
template <class F>
void resolve(void* lib, const char* name, F& f, std::string& error) {
    f = reinterpret_cast<F>(dlsym(lib, name));
    if (!f && error.empty()) error = std::string("no ") + name + " in the platform library";
}

#ifdef SSSLAB_GL_OSMESA
struct OsmesaApi {
    decltype(&::OSMesaCreateContextAttribs) create = nullptr;
    decltype(&::OSMesaMakeCurrent) make_current = nullptr;
    decltype(&::OSMesaGetProcAddress) get_proc = nullptr;
    decltype(&::OSMesaDestroyContext) destroy = nullptr;
    std::string error;  ///< why the library is not usable (empty: it is)
};
const OsmesaApi& osmesa() {
    static const OsmesaApi api = [] {
        OsmesaApi a;
        void* lib = open_first({"libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"}, a.error);
        if (!lib) return a;
        resolve(lib, "OSMesaCreateContextAttribs", a.create, a.error);
        resolve(lib, "OSMesaMakeCurrent", a.make_current, a.error);
        resolve(lib, "OSMesaGetProcAddress", a.get_proc, a.error);
        resolve(lib, "OSMesaDestroyContext", a.destroy, a.error);
        return a;
    }();
    return api;
}
#endif

#ifdef SSSLAB_GL_EGL
struct EglApi {
    decltype(&::eglGetProcAddress) get_proc = nullptr;
    decltype(&::eglQueryString) query_string = nullptr;
    decltype(&::eglInitialize) initialize = nullptr;
    decltype(&::eglBindAPI) bind_api = nullptr;
    decltype(&::eglChooseConfig) choose_config = nullptr;
    decltype(&::eglCreateContext) create_context = nullptr;
    decltype(&::eglMakeCurrent) make_current = nullptr;
    decltype(&::eglGetCurrentContext) current_context = nullptr;
    decltype(&::eglDestroyContext) destroy_context = nullptr;
    std::string error;
};
const EglApi& egl() {
    static const EglApi api = [] {
        EglApi a;
        void* lib = open_first({"libEGL.so.1", "libEGL.so"}, a.error);
        if (!lib) return a;
        resolve(lib, "eglGetProcAddress", a.get_proc, a.error);
        resolve(lib, "eglQueryString", a.query_string, a.error);
        resolve(lib, "eglInitialize", a.initialize, a.error);
        resolve(lib, "eglBindAPI", a.bind_api, a.error);
        resolve(lib, "eglChooseConfig", a.choose_config, a.error);
        resolve(lib, "eglCreateContext", a.create_context, a.error);
        resolve(lib, "eglMakeCurrent", a.make_current, a.error);
        resolve(lib, "eglGetCurrentContext", a.current_context, a.error);
        resolve(lib, "eglDestroyContext", a.destroy_context, a.error);
        return a;
    }();
    return api;
}
#endif

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
    OSMesaContext osmesa_ctx = nullptr;
    unsigned char pixel[4] = {0, 0, 0, 0};  // the 1 x 1 buffer OSMesa is made current on
#endif
#ifdef SSSLAB_GL_EGL
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext egl_ctx = EGL_NO_CONTEXT;
#endif
    bool is_osmesa = false;

    void make_current() const {
#ifdef SSSLAB_GL_OSMESA
        if (is_osmesa) {
            if (!osmesa().make_current(osmesa_ctx, const_cast<unsigned char*>(pixel),
                                       GL_UNSIGNED_BYTE, 1, 1))
                throw std::runtime_error("OSMesaMakeCurrent failed");
            return;
        }
#endif
#ifdef SSSLAB_GL_EGL
        if (!egl().make_current(display, EGL_NO_SURFACE, EGL_NO_SURFACE, egl_ctx))
            throw std::runtime_error("eglMakeCurrent (surfaceless) failed");
#endif
    }
    void load() const {
        int version = 0;
#ifdef SSSLAB_GL_OSMESA
        if (is_osmesa) version = gladLoadGL(reinterpret_cast<GLADloadfunc>(osmesa().get_proc));
#endif
#ifdef SSSLAB_GL_EGL
        if (!is_osmesa) version = gladLoadGL(reinterpret_cast<GLADloadfunc>(egl().get_proc));
#endif
        if (version == 0) throw std::runtime_error("the GL loader (glad) found no OpenGL");
        if (GLAD_VERSION_MAJOR(version) * 10 + GLAD_VERSION_MINOR(version) < 33)
            throw std::runtime_error("OpenGL " + std::to_string(GLAD_VERSION_MAJOR(version)) + "." +
                                     std::to_string(GLAD_VERSION_MINOR(version)) +
                                     ": the GL twin needs 3.3 core");
    }
    ~Impl() {
#ifdef SSSLAB_GL_OSMESA
        if (osmesa_ctx) osmesa().destroy(osmesa_ctx);
#endif
#ifdef SSSLAB_GL_EGL
        if (egl_ctx != EGL_NO_CONTEXT) {
            if (egl().current_context() == egl_ctx)
                egl().make_current(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            egl().destroy_context(display, egl_ctx);
        }
        // The display is not terminated: EGL displays are per process and per device, and
        // terminating one would end every other context on it.
#endif
    }
};

namespace {

#ifdef SSSLAB_GL_OSMESA
std::unique_ptr<GlContext::Impl> make_osmesa(std::string& why) {
    if (!osmesa().error.empty()) {
        why = osmesa().error;
        return nullptr;
    }
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
    impl->osmesa_ctx = osmesa().create(attribs, nullptr);
    if (!impl->osmesa_ctx) {
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
    if (!egl().initialize(display, &major, &minor)) {
        why = "eglInitialize failed";
        return nullptr;
    }
    if (!egl().bind_api(EGL_OPENGL_API)) {
        why = "egl().bind_api(EGL_OPENGL_API) failed";
        return nullptr;
    }
    // No surface type asked for (the default, EGL_WINDOW_BIT, has no config without a window
    // system).
    const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, 0,
                                     EGL_NONE};
    EGLConfig config = nullptr;
    EGLint n = 0;
    if (!egl().choose_config(display, config_attribs, &config, 1, &n) || n < 1) {
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
    impl->egl_ctx = egl().create_context(display, config, EGL_NO_CONTEXT, ctx_attribs);
    if (impl->egl_ctx == EGL_NO_CONTEXT) {
        why = "eglCreateContext gave no OpenGL 3.3 core context";
        return nullptr;
    }
    return impl;
}

// EGL's device platform with a hardware device (skipping Mesa's software device), or null.
std::unique_ptr<GlContext::Impl> make_egl_device(std::string& why) {
    if (!egl().error.empty()) {
        why = egl().error;
        return nullptr;
    }
    const char* client = egl().query_string(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!client || !std::strstr(client, "EGL_EXT_device_enumeration") ||
        !std::strstr(client, "EGL_EXT_platform_device")) {
        why = "EGL has no device enumeration";
        return nullptr;
    }
    auto query_devices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(egl().get_proc("eglQueryDevicesEXT"));
    auto device_string =
        reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(egl().get_proc("eglQueryDeviceStringEXT"));
    auto platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        egl().get_proc("eglGetPlatformDisplayEXT"));
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
    if (!egl().error.empty()) {
        why = egl().error;
        return nullptr;
    }
    auto platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        egl().get_proc("eglGetPlatformDisplayEXT"));
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
    // The ways to a context, in the order kAuto tries them.
    using Maker = std::unique_ptr<GlContext::Impl> (*)(std::string&);
    struct Way {
        const char* name;
        GlPlatform platform;
        Maker make;
    };
    const std::vector<Way> ways = {
#ifdef SSSLAB_GL_EGL
        {"egl-device", GlPlatform::kEgl, make_egl_device},
#endif
#ifdef SSSLAB_GL_OSMESA
        {"osmesa", GlPlatform::kOsmesa, make_osmesa},
#endif
#ifdef SSSLAB_GL_EGL
        {"egl-surfaceless", GlPlatform::kEgl, make_egl_surfaceless},
#endif
    };
    std::unique_ptr<GlContext::Impl> impl;
    std::string name, reasons;
    for (const Way& way : ways) {
        if (platform != GlPlatform::kAuto && platform != way.platform) continue;
        std::string w;
        impl = way.make(w);
        if (impl) {
            name = way.name;
            break;
        }
        reasons += (reasons.empty() ? "" : "; ") + std::string(way.name) + ": " + w;
    }
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
