#include "realtime/gl/bssrdf_gl.h"

#include "approx/tabulated_profile.h"
#include "core/error.h"
#include "realtime/gl/gl_util.h"
#include "realtime/gl/shaders.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace ssslab::realtime::gl {
namespace {

using approx::BssrdfFile;
using approx::BssrdfParameter;
using approx::BssrdfSection;

constexpr int kWidth = 1024;       // texels a row of the radii and results
constexpr int kAppLine = 1000000;  // the application's code is counted from here up

/// A section's code, preceded by a #line directive so that the compiler counts the file's lines
/// (GLSL 3.30 §3.3: after `#line L S` the next line is line L of source string S).
std::string with_line(const BssrdfSection& s) {
    return "#line " + std::to_string(s.first_line) + " 1\n" + s.code + "\n";
}

std::string fragment_source(const BssrdfFile& f) {
    std::ostringstream os;
    os << "#version 330 core\n#line " << 2 * kAppLine
       << " 0\n"
          "uniform vec3 SigmaA;\nuniform vec3 SigmaS;\nuniform float G;\nuniform float IOR;\n"
          "const float PI = 3.14159265358979323846;\n";
    for (const BssrdfParameter& p : f.parameters)
        os << "uniform "
           << (p.type == BssrdfParameter::Type::kFloat  ? "float "
               : p.type == BssrdfParameter::Type::kBool ? "bool "
                                                        : "vec3 ")
           << p.name << ";\n";
    os << "uniform sampler2D ssslab_radii;\nuniform int ssslab_count;\n"
          "uniform vec3 ssslab_alpha_prime;\nout vec4 ssslab_out;\n";
    if (f.initializer)
        os << with_line(*f.initializer);
    else
        os << "void init() {}\n";
    if (f.diffuse_reflectance) os << with_line(*f.diffuse_reflectance);
    os << with_line(*f.shader);
    os << "#line " << kAppLine
       << " 0\nvoid main() {\n"
          "    ivec2 p = ivec2(gl_FragCoord.xy);\n"
          "    int i = p.y * "
       << kWidth
       << " + p.x;\n"
          "    init();\n"
          "    vec3 n = vec3(0.0, 0.0, 1.0);\n"
          "    if (i < ssslab_count) {\n"
          "        float r = texelFetch(ssslab_radii, p, 0).r;\n"
          "        ssslab_out = vec4(Bssrdf(vec3(r, 0.0, 0.0), n, vec3(0.0), n), 1.0);\n"
          "    }\n";
    if (f.diffuse_reflectance)
        os << "    else if (i == ssslab_count)\n"
              "        ssslab_out = vec4(DiffuseReflectance(ssslab_alpha_prime), 1.0);\n";
    os << "    else ssslab_out = vec4(0.0);\n}\n";
    return os.str();
}

/// The file line of a compiler message: the L of the first "S:L" or "S(L" in it (Mesa
/// "0:12(5): error: ...", NVIDIA "0(12) : error C1008: ...", others "ERROR: 0:12: ..."); 0 if
/// none. Drivers differ in the source string they print after `#line L S` (Mesa printed 0 for one
/// section and 1 for the next), so the line alone locates: the application's own code is counted
/// from kAppLine, above any file's lines.
int message_line(const std::string& msg) {
    for (size_t i = 0; i < msg.size(); ++i) {
        if (!std::isdigit(static_cast<unsigned char>(msg[i])) ||
            (i > 0 && std::isalnum(static_cast<unsigned char>(msg[i - 1]))))
            continue;
        size_t j = i;
        while (j < msg.size() && std::isdigit(static_cast<unsigned char>(msg[j]))) ++j;
        if (j + 1 < msg.size() && (msg[j] == ':' || msg[j] == '(') &&
            std::isdigit(static_cast<unsigned char>(msg[j + 1])))
            return std::atoi(msg.c_str() + j + 1);
        i = j;
    }
    return 0;
}

/// The compiler's first error, at the file's line (the shader section's first line for an error
/// in the application's code, e.g. a Bssrdf() of the wrong signature).
[[noreturn]] void throw_compile_error(const BssrdfFile& f, const std::string& log) {
    std::istringstream is(log);
    std::string msg, first;
    while (std::getline(is, msg)) {
        if (first.empty()) first = msg;
        if (msg.find("error") != std::string::npos || msg.find("ERROR") != std::string::npos) {
            first = msg;
            break;
        }
    }
    int line = message_line(first);
    if (line <= 0 || line >= kAppLine) line = f.shader->first_line;
    throw InputError({f.path, line, 0}, "", "GLSL does not compile: " + first);
}

struct Program {
    GLuint id = 0;
    ~Program() {
        if (id) glDeleteProgram(id);
    }
};

/// The draw's objects: a w x h texture of radii in, one of RGBA results out and its framebuffer,
/// an empty vertex array; released (and the default framebuffer bound) however the draw ends.
struct Targets {
    GLuint vao = 0, in = 0, out = 0;
    GlFramebuffer fb;
    Targets(int w, int h, const float* radii, const std::string& what) {
        glGenVertexArrays(1, &vao);
        in = make_texture(w, h, GL_R32F, GL_RED, GL_FLOAT, radii);
        out = make_texture(w, h, GL_RGBA32F, GL_RGBA, GL_FLOAT, nullptr);
        fb = make_framebuffer(w, h, {out}, false, what);
    }
    ~Targets() {
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        release_framebuffer(fb);
        glDeleteTextures(1, &in);
        glDeleteTextures(1, &out);
        glDeleteVertexArrays(1, &vao);
    }
    Targets(const Targets&) = delete;
    Targets& operator=(const Targets&) = delete;
};

GLuint compile_bssrdf(const BssrdfFile& file) {
    require_gl(3, 3, "a .bssrdf file's GLSL needs OpenGL 3.3");
    try {
        return link_program(shaders::fullscreen_vert, fragment_source(file), file.path);
    } catch (const GlShaderError& e) {
        throw_compile_error(file, e.log);
    }
}

}  // namespace

void check_bssrdf(const BssrdfFile& file, GlPlatform platform) {
    approx::require_radial_profile(file);
    const auto context = GlContext::create(platform);
    Program prog;
    prog.id = compile_bssrdf(file);
}

BssrdfValues evaluate_bssrdf(const BssrdfFile& file, const approx::DiffusionMedium& m, int channel,
                             const std::vector<double>& radii,
                             const BssrdfParameterValues& values) {
    approx::require_radial_profile(file);
    if (channel < 0 || channel > 2) throw std::invalid_argument("evaluate_bssrdf: channel not 0-2");
    for (const auto& [name, v] : values) {
        const BssrdfParameter* p = file.find_parameter(name);
        if (!p) throw std::invalid_argument(file.path + ": no parameter '" + name + "'");
        if (p->type == BssrdfParameter::Type::kFloat && !(v[0] >= p->min && v[0] <= p->max)) {
            std::ostringstream os;
            os << file.path << ": parameter '" << name << "' = " << v[0] << " is outside ["
               << p->min << ", " << p->max << "]";
            throw std::invalid_argument(os.str());
        }
    }
    Program prog;
    prog.id = compile_bssrdf(file);
    const int n = static_cast<int>(radii.size());
    const int slots = n + 1;  // the radii and DiffuseReflectance
    const int h = (slots + kWidth - 1) / kWidth;
    std::vector<float> r(static_cast<size_t>(kWidth) * static_cast<size_t>(h), 0.0f);
    for (int i = 0; i < n; ++i)
        r[static_cast<size_t>(i)] = static_cast<float>(radii[static_cast<size_t>(i)]);

    std::vector<float> rgba(static_cast<size_t>(kWidth) * static_cast<size_t>(h) * 4);
    {
        const Targets t(kWidth, h, r.data(), file.path);
        glUseProgram(prog.id);
        const auto loc = [&](const std::string& name) {
            return glGetUniformLocation(prog.id, name.c_str());
        };
        const auto splat = [&](const char* name, double v) {
            glUniform3f(loc(name), static_cast<float>(v), static_cast<float>(v),
                        static_cast<float>(v));
        };
        splat("SigmaA", m.sigma_a);
        splat("SigmaS", m.sigma_s);
        glUniform1f(loc("G"), static_cast<float>(m.g));
        glUniform1f(loc("IOR"), static_cast<float>(m.eta));
        splat("ssslab_alpha_prime", m.sigma_s_reduced() / m.sigma_t_reduced());
        glUniform1i(loc("ssslab_count"), n);
        for (const BssrdfParameter& p : file.parameters) {
            const auto it = values.find(p.name);
            const std::array<double, 3> v = it == values.end() ? p.fallback : it->second;
            // An unused uniform is optimised away (location -1): glUniform ignores -1.
            if (p.type == BssrdfParameter::Type::kFloat)
                glUniform1f(loc(p.name), static_cast<float>(v[0]));
            else if (p.type == BssrdfParameter::Type::kBool)
                glUniform1i(loc(p.name), v[0] != 0 ? 1 : 0);
            else
                glUniform3f(loc(p.name), static_cast<float>(v[0]), static_cast<float>(v[1]),
                            static_cast<float>(v[2]));
        }
        bind_texture(prog.id, "ssslab_radii", 0, t.in);
        glBindFramebuffer(GL_FRAMEBUFFER, t.fb.fbo);
        glViewport(0, 0, kWidth, h);
        glDisable(GL_BLEND);
        glDisable(GL_DEPTH_TEST);
        glBindVertexArray(t.vao);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glReadPixels(0, 0, kWidth, h, GL_RGBA, GL_FLOAT, rgba.data());
        check_gl("evaluating a .bssrdf file");
    }

    BssrdfValues v;
    const auto at = [&](int i) {
        return static_cast<double>(rgba[static_cast<size_t>(i) * 4 + static_cast<size_t>(channel)]);
    };
    for (int i = 0; i < n; ++i) {
        v.rd.push_back(at(i));
        if (!std::isfinite(v.rd.back())) {
            std::ostringstream os;
            os.precision(9);
            os << file.path << ": Bssrdf() at r = " << radii[static_cast<size_t>(i)] << " is "
               << v.rd.back() << " (not a finite number)";
            throw std::runtime_error(os.str());
        }
    }
    if (file.diffuse_reflectance) v.diffuse_reflectance = at(n);
    return v;
}

std::unique_ptr<approx::DiffusionProfile> make_bssrdf_profile(
    const BssrdfFile& file, const std::string& name, const approx::DiffusionMedium& m, int channel,
    const BssrdfParameterValues& values, GlPlatform platform) {
    approx::validate(m, approx::FresnelMoments::exact);
    const double l = 1 / m.sigma_t_reduced();
    const double r_min = 1e-6 * l, r_max = 1e6 * l;
    const auto context = GlContext::create(platform);
    const BssrdfValues v = evaluate_bssrdf(
        file, m, channel, approx::TabulatedProfile::radii(r_min, r_max, kBssrdfTableRadii), values);
    // Float arithmetic: values accurate to about 1e-6 relative (test_bssrdf_gl states the bound).
    return std::make_unique<approx::TabulatedProfile>(name, m, r_min, r_max, v.rd, false, 1e-6);
}

}  // namespace ssslab::realtime::gl
