#include "realtime/gl/sss_pass_gl.h"

#include <glad/gl.h>

#include "approx/convolve.h"
#include "realtime/gl/gl_util.h"
#include "realtime/gl/shaders.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>

namespace ssslab::realtime::gl {

namespace {

// The shader's MODE of an edge mode (shaders/sss_pass.frag).
int shader_mode(SssEdgeMode m) {
    return m == SssEdgeMode::kNone ? 0 : m == SssEdgeMode::kFollowSurface ? 1 : 2;
}

}  // namespace

struct GlSssPass::Impl {
    GlContext& ctx;
    GLuint vao = 0;
    // Programs per (mode, jitter, rotate, phase).
    std::map<std::tuple<int, bool, bool, int>, GLuint> programs;
    std::unique_ptr<GlTimer> timer;
    bool precise = false;  // GLSL 4.00: tap positions in double (shaders/sss_pass.frag)

    // The uploaded inputs of one run and the targets.
    struct Resident {
        int w = 0, h = 0, rank = 0;
        GLuint input = 0, mat = 0, taps = 0, jit = 0, meta = 0;
        GLuint tmp = 0, acc[2] = {0, 0};
        GLuint fbo = 0;
    };

    explicit Impl(GlContext& c) : ctx(c) {
        ctx.make_current();
        glGenVertexArrays(1, &vao);
        timer = std::make_unique<GlTimer>();
        GLint major = 0;
        glGetIntegerv(GL_MAJOR_VERSION, &major);
        precise = major >= 4;
        check_gl("GlSssPass set-up");
    }
    ~Impl() {
        ctx.make_current();
        for (auto& [k, p] : programs) glDeleteProgram(p);
        timer.reset();
        glDeleteVertexArrays(1, &vao);
    }

    GLuint program(int mode, bool jitter, bool rotate, int phase) {
        const auto key = std::make_tuple(mode, jitter, rotate, phase);
        auto it = programs.find(key);
        if (it != programs.end()) return it->second;
        const std::string defines =
            std::string(precise ? "#version 400 core\n" : "#version 330 core\n") +
            "#define PRECISE " + (precise ? "1" : "0") + "\n#define MODE " + std::to_string(mode) +
            "\n#define JITTER " + (jitter ? "1" : "0") + "\n#define ROTATE " +
            (rotate ? "1" : "0") + "\n#define PHASE " + std::to_string(phase) + "\n";
        const GLuint p =
            link_program(shaders::fullscreen_vert, defines + shaders::sss_pass_frag,
                         "realtime/gl/shaders/sss_pass.frag (MODE " + std::to_string(mode) +
                             ", JITTER " + (jitter ? "1" : "0") + ", ROTATE " +
                             (rotate ? "1" : "0") + ", PHASE " + std::to_string(phase) + ")");
        programs.emplace(key, p);
        return p;
    }

    Resident upload(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
                    const SssParams& p) {
        Resident r;
        r.w = g.width;
        r.h = g.height;
        for (const SssMaterialKernel& m : materials)
            r.rank = std::max(r.rank, static_cast<int>(m.terms.size()));
        const size_t n = g.pixels();
        std::vector<float> rgbz(4 * n);
        for (size_t i = 0; i < n; ++i) {
            rgbz[4 * i] = g.irradiance[3 * i];
            rgbz[4 * i + 1] = g.irradiance[3 * i + 1];
            rgbz[4 * i + 2] = g.irradiance[3 * i + 2];
            rgbz[4 * i + 3] = g.view_z[i];
        }
        r.input = make_texture(r.w, r.h, GL_RGBA32F, GL_RGBA, GL_FLOAT, rgbz.data());
        r.mat = make_texture(r.w, r.h, GL_R32I, GL_RED_INTEGER, GL_INT, g.material.data());
        // Taps, jitter ranges and per-term numbers, one row per (material, term).
        size_t count = 1;
        for (const SssMaterialKernel& m : materials)
            for (const SssTerm& t : m.terms) count = std::max(count, t.taps.offset_mm.size());
        const int rows = std::max<int>(1, static_cast<int>(materials.size()) * r.rank);
        std::vector<float> taps(4 * count * static_cast<size_t>(rows), 0.0f);
        std::vector<float> jit(4 * count * static_cast<size_t>(rows), 0.0f);
        std::vector<float> meta(4 * 4 * static_cast<size_t>(rows), 0.0f);
        for (size_t m = 0; m < materials.size(); ++m)
            for (size_t k = 0; k < materials[m].terms.size(); ++k) {
                const SssTerm& t = materials[m].terms[k];
                const size_t row = m * static_cast<size_t>(r.rank) + k;
                const approx::TapJitterRange range = approx::tap_jitter_range(t.taps, p.jitter);
                std::array<double, 3> sum{};
                for (size_t i = 0; i < t.taps.offset_mm.size(); ++i) {
                    float* q = &taps[4 * (row * count + i)];
                    q[0] = static_cast<float>(t.taps.offset_mm[i]);
                    float* j = &jit[4 * (row * count + i)];
                    j[0] = static_cast<float>(range.left_mm[i]);
                    j[1] = static_cast<float>(range.right_mm[i]);
                    j[2] = static_cast<float>(t.taps.offset_mm[i] - q[0]);  // the remainder
                    for (int ch = 0; ch < 3; ++ch) {
                        q[1 + ch] = static_cast<float>(t.taps.weight[ch][i]);
                        sum[ch] += t.taps.weight[ch][i];
                    }
                }
                float* e = &meta[4 * 4 * row];
                e[0] = static_cast<float>(t.taps.offset_mm.size());
                e[1] = static_cast<float>(t.taps.support_mm);
                e[2] = static_cast<float>(t.taps.support_mm - e[1]);
                for (int ch = 0; ch < 3; ++ch) {
                    e[4 + ch] = static_cast<float>(sum[ch]);
                    e[12 + ch] = static_cast<float>(sum[ch] - e[4 + ch]);
                    e[8 + ch] = static_cast<float>(t.sign[ch]);
                }
            }
        r.taps =
            make_texture(static_cast<int>(count), rows, GL_RGBA32F, GL_RGBA, GL_FLOAT, taps.data());
        r.jit =
            make_texture(static_cast<int>(count), rows, GL_RGBA32F, GL_RGBA, GL_FLOAT, jit.data());
        r.meta = make_texture(4, rows, GL_RGBA32F, GL_RGBA, GL_FLOAT, meta.data());
        r.tmp = make_texture(r.w, r.h, GL_RGBA32F, GL_RGBA, GL_FLOAT, nullptr);
        r.acc[0] = make_texture(r.w, r.h, GL_RGBA32F, GL_RGBA, GL_FLOAT, nullptr);
        r.acc[1] = make_texture(r.w, r.h, GL_RGBA32F, GL_RGBA, GL_FLOAT, nullptr);
        glGenFramebuffers(1, &r.fbo);
        check_gl("GlSssPass upload");
        return r;
    }

    void release(Resident& r) {
        const GLuint tex[] = {r.input, r.mat, r.taps, r.jit, r.meta, r.tmp, r.acc[0], r.acc[1]};
        glDeleteTextures(8, tex);
        glDeleteFramebuffers(1, &r.fbo);
        r = Resident{};
    }

    // The draws of the pass on resident inputs; returns the texture that holds the result.
    GLuint draw(const Resident& r, const SssParams& p) {
        const int mode = shader_mode(p.mode);
        const bool jitter = p.jitter > 0;
        // Kernel scale [Freude14 Eq. 4.11]: pixels per mm at view depth 1, along x and y.
        const double px = r.w / (2.0 * p.tan_half * p.aspect * p.unit_mm);
        const double py = r.h / (2.0 * p.tan_half * p.unit_mm);
        glBindVertexArray(vao);
        glBindFramebuffer(GL_FRAMEBUFFER, r.fbo);
        glViewport(0, 0, r.w, r.h);
        glDisable(GL_BLEND);
        glDisable(GL_DEPTH_TEST);
        GLuint result = r.input;  // rank 0: the input passes through
        for (int k = 0; k < r.rank; ++k) {
            for (int phase = 0; phase < 2; ++phase) {
                const GLuint prog = program(mode, jitter, p.rotate, phase);
                glUseProgram(prog);
                const GLuint target = phase == 0 ? r.tmp : r.acc[k % 2];
                glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, target,
                                       0);
                bind_texture(prog, "u_src", 0, phase == 0 ? r.input : r.tmp);
                bind_texture(prog, "u_input", 1, r.input);
                bind_texture(prog, "u_prev", 2, k > 0 ? r.acc[(k + 1) % 2] : r.input);
                bind_texture(prog, "u_mat", 3, r.mat);
                bind_texture(prog, "u_taps", 4, r.taps);
                bind_texture(prog, "u_jit", 5, r.jit);
                bind_texture(prog, "u_meta", 6, r.meta);
                glUniform1i(glGetUniformLocation(prog, "u_term"), k);
                glUniform1i(glGetUniformLocation(prog, "u_rank"), r.rank);
                glUniform2i(glGetUniformLocation(prog, "u_size"), r.w, r.h);
                if (precise)
                    glUniform2d(glGetUniformLocation(prog, "u_per_mm_z"), px, py);
                else
                    glUniform2f(glGetUniformLocation(prog, "u_per_mm_z"), static_cast<float>(px),
                                static_cast<float>(py));
                glUniform1f(glGetUniformLocation(prog, "u_follow"),
                            static_cast<float>(p.follow_strength / p.tan_half));
                glUniform1f(glGetUniformLocation(prog, "u_reject"),
                            static_cast<float>(p.reject_depth));
                glUniform1ui(glGetUniformLocation(prog, "u_seed"), p.seed);
                glDrawArrays(GL_TRIANGLES, 0, 3);
                result = target;
            }
        }
        check_gl("GlSssPass draw");
        return result;
    }

    void read(const Resident& r, GLuint tex, std::vector<float>& out) {
        glBindFramebuffer(GL_FRAMEBUFFER, r.fbo);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        const size_t n = static_cast<size_t>(r.w) * r.h;
        std::vector<float> rgba(4 * n);
        glReadPixels(0, 0, r.w, r.h, GL_RGBA, GL_FLOAT, rgba.data());
        check_gl("GlSssPass read-back");
        out.resize(3 * n);
        for (size_t i = 0; i < n; ++i)
            for (int ch = 0; ch < 3; ++ch) out[3 * i + ch] = rgba[4 * i + ch];
    }
};

// The inputs checked and uploaded and the programs compiled (outside any timer query); the
// uploads are released when it goes out of scope, whatever happens.
struct Prepared {
    GlSssPass::Impl& m;
    GlSssPass::Impl::Resident r;
    Prepared(GlSssPass::Impl& impl, const SssGBuffer& g,
             const std::vector<SssMaterialKernel>& materials, const SssParams& p)
        : m(impl) {
        check_sss_inputs(g, materials, p);
        for (size_t i = 0; i < g.pixels(); ++i)
            if (!sss_pixel_ok(g.material[i], g.view_z[i], materials.size()))
                refuse_sss_pixel(g, materials.size(), i);
        m.ctx.make_current();
        r = m.upload(g, materials, p);
        for (int phase = 0; phase < 2; ++phase)
            m.program(shader_mode(p.mode), p.jitter > 0, p.rotate, phase);
        glFinish();
    }
    ~Prepared() { m.release(r); }
    Prepared(const Prepared&) = delete;
    Prepared& operator=(const Prepared&) = delete;
};

GlSssPass::GlSssPass(GlContext& context) : impl_(std::make_unique<Impl>(context)) {}
GlSssPass::~GlSssPass() = default;

void GlSssPass::run(const SssGBuffer& g, const std::vector<SssMaterialKernel>& materials,
                    const SssParams& p, std::vector<float>& out, GlSssTimes* times) {
    const auto t0 = std::chrono::steady_clock::now();
    Prepared in(*impl_, g, materials, p);
    const double upload = ms_since(t0);
    impl_->timer->begin();
    const GLuint result = impl_->draw(in.r, p);
    impl_->timer->end();
    const auto t1 = std::chrono::steady_clock::now();
    impl_->read(in.r, result, out);
    const double readback = ms_since(t1);
    if (times) {
        times->gpu_ms = impl_->timer->gpu_ms();
        times->draw_ms = impl_->timer->wall_ms();
        times->upload_ms = upload;
        times->readback_ms = readback;
        times->wall_ms = ms_since(t0);
    }
}

std::vector<GlSssTimes> GlSssPass::time_runs(const SssGBuffer& g,
                                             const std::vector<SssMaterialKernel>& materials,
                                             const SssParams& p, int repeat) {
    Prepared in(*impl_, g, materials, p);
    impl_->draw(in.r, p);  // a draw before the timed ones (llvmpipe compiles shaders lazily)
    glFinish();
    std::vector<GlSssTimes> ms;
    for (int i = 0; i < repeat; ++i) {
        impl_->timer->begin();
        impl_->draw(in.r, p);
        impl_->timer->end();
        GlSssTimes t;
        t.gpu_ms = impl_->timer->gpu_ms();
        t.draw_ms = t.wall_ms = impl_->timer->wall_ms();
        ms.push_back(t);
    }
    return ms;
}

}  // namespace ssslab::realtime::gl
