#include "realtime/gl/lighting_gl.h"

#include "realtime/gl/gl_util.h"
#include "realtime/gl/shaders.h"
#include "realtime/shadow_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>

namespace ssslab::realtime::gl {

namespace {

constexpr int kMaxSpheres = 16, kMaxSuns = 8, kMaxViews = 6;

// The lighting programs' source: lighting_common.glsl after the version line.
std::string lighting_source(const char* frag) {
    return std::string("#version 400 core\n") + shaders::lighting_common_glsl + "\n" + frag;
}

void set(GLuint p, const char* name, const Vec3& v) {
    glUniform3f(glGetUniformLocation(p, name), static_cast<float>(v.x), static_cast<float>(v.y),
                static_cast<float>(v.z));
}
void set(GLuint p, const char* name, const std::array<double, 3>& v) {
    set(p, name, Vec3{v[0], v[1], v[2]});
}
void set(GLuint p, const char* name, double v) {
    glUniform1f(glGetUniformLocation(p, name), static_cast<float>(v));
}
void set_int(GLuint p, const char* name, int v) {
    glUniform1i(glGetUniformLocation(p, name), v);
}
void set_at(GLuint p, const std::string& name, int k, const Vec3& v) {
    set(p, (name + "[" + std::to_string(k) + "]").c_str(), v);
}

struct ShadowTargets {
    GLuint depth = 0, shape = 0;  // ShadowMap::depth, ShadowMap::shape
    GlFramebuffer fb;
};

}  // namespace

struct GlLighting::Impl {
    GlContext& ctx;
    GLuint receiver = 0, light = 0, shadow = 0, vao = 0;
    std::unique_ptr<GlTimer> timer;
    // The G-buffer's targets at w x h: irradiance, specular, surface, translucency (+thickness),
    // normal (+exit weight) as RGBA32F, kind and material as RG32I.
    // fb: all six (the receiver pass); fb_light: the first four, blended by the light passes,
    // which read the last two as textures.
    GlFramebuffer fb, fb_light;
    std::array<GLuint, 6> targets{};
    int w = 0, h = 0;
    std::map<int, ShadowTargets> maps;  // by size

    explicit Impl(GlContext& c) : ctx(c) {
        ctx.make_current();
        require_gl(4, 5, "the GL lighting needs OpenGL 4.5 (glClipControl for its shadow maps)");
        receiver =
            link_program(shaders::fullscreen_vert, lighting_source(shaders::lighting_receiver_frag),
                         "realtime/gl/shaders/lighting_receiver.frag");
        light =
            link_program(shaders::fullscreen_vert, lighting_source(shaders::lighting_light_frag),
                         "realtime/gl/shaders/lighting_light.frag");
        shadow = link_program(shaders::shadow_vert, shaders::shadow_frag,
                              "realtime/gl/shaders/shadow.{vert,frag}");
        glGenVertexArrays(1, &vao);
        timer = std::make_unique<GlTimer>();
        check_gl("GlLighting set-up");
    }
    ~Impl() {
        ctx.make_current();
        release_targets();
        for (auto& [size, t] : maps) {
            const GLuint tex[] = {t.depth, t.shape};
            glDeleteTextures(2, tex);
            release_framebuffer(t.fb);
        }
        timer.reset();
        glDeleteVertexArrays(1, &vao);
        glDeleteProgram(receiver);
        glDeleteProgram(light);
        glDeleteProgram(shadow);
    }
    void release_targets() {
        glDeleteTextures(static_cast<GLsizei>(targets.size()), targets.data());
        release_framebuffer(fb);
        release_framebuffer(fb_light);
        targets = {};
        fb = fb_light = {};
        w = h = 0;
    }
    void gbuffer_targets(int width, int height) {
        if (width == w && height == h) return;
        release_targets();
        w = width;
        h = height;
        for (int k = 0; k < 5; ++k)
            targets[static_cast<size_t>(k)] =
                make_texture(w, h, GL_RGBA32F, GL_RGBA, GL_FLOAT, nullptr);
        targets[5] = make_texture(w, h, GL_RG32I, GL_RG_INTEGER, GL_INT, nullptr);
        fb = make_framebuffer(w, h, {targets.begin(), targets.end()}, false,
                              "GlLighting's G-buffer");
        fb_light = make_framebuffer(w, h, {targets.begin(), targets.begin() + 4}, false,
                                    "GlLighting's light passes");
    }
    const ShadowTargets& shadow_targets(int size) {
        auto it = maps.find(size);
        if (it != maps.end()) return it->second;
        ShadowTargets t;
        t.depth = make_texture(size, size, GL_R32F, GL_RED, GL_FLOAT, nullptr);
        t.shape = make_texture(size, size, GL_R32I, GL_RED_INTEGER, GL_INT, nullptr);
        t.fb = make_framebuffer(size, size, {t.depth, t.shape}, true, "GlLighting's shadow map");
        return maps.emplace(size, t).first->second;
    }
};

GlLighting::GlLighting(GlContext& context) : impl_(std::make_unique<Impl>(context)) {}
GlLighting::~GlLighting() = default;

void GlLighting::shade(const Scene& scene, const RasterCamera& camera, const RasterFrame& frame,
                       const LightingOptions& o, const std::vector<SlabTransmittance>& slabs,
                       LightingStats* stats, GBuffer& g, GlLightingTimes* times) {
    const auto t_start = std::chrono::steady_clock::now();
    check_lighting_inputs(camera, frame, o);
    // What camera and reflection rays see of the lights, as uniforms: their surfaces (spheres),
    // the cones escaping rays see them in (suns' discs) and the environment (the whole sphere).
    const std::vector<Light> lights(scene.lights.begin(), scene.lights.end());
    int spheres = 0, suns = 0;
    for (const Light& l : lights) {
        Vec3 axis;
        double cos_half = 0;
        spheres += l.has_surface();
        suns += l.escape_cone(axis, cos_half) && cos_half > -1;
    }
    if (spheres > kMaxSpheres || suns > kMaxSuns)
        throw std::invalid_argument("the GL lighting takes at most " + std::to_string(kMaxSpheres) +
                                    " sphere lights and " + std::to_string(kMaxSuns) +
                                    " suns with a disc");
    Impl& m = *impl_;
    m.ctx.make_current();
    const int ss = frame.supersample;
    const int W = frame.sample_width(), H = frame.sample_height();
    const size_t N = static_cast<size_t>(W) * static_cast<size_t>(H);
    const RasterCamera::SampleRays rays = camera.sample_rays(ss);
    const Vec3 cam = camera.position;
    GlLightingTimes t;

    // ---- Uploads: the G-buffer's geometry (GL rows: the frame's last row first), the camera's
    // rays, facets, materials and their tables, the meshes for the shadow maps.
    auto t0 = std::chrono::steady_clock::now();
    std::vector<float> fz(N), ft(N);
    std::vector<std::int32_t> fshape(N), ftri(N);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t k = frame.sample_index(x, y);
            const size_t gi = static_cast<size_t>(H - 1 - y) * W + x;
            fz[gi] = static_cast<float>(frame.view_z[k]);
            ft[gi] = static_cast<float>(frame.ray_t[k]);
            fshape[gi] = frame.shape[k];
            ftri[gi] = frame.shape[k] >= 0 ? static_cast<std::int32_t>(frame.triangle[k]) : 0;
        }
    // Everything uploaded is released on every exit (an exception in a later pass included).
    std::vector<GLuint> tex;
    std::array<GLuint, 2> buf{}, tbo{};
    std::vector<GlMesh> meshes;
    struct Release {
        std::function<void()> f;
        ~Release() { f(); }
    } release{[&] {
        for (const GlMesh& mm : meshes) release_mesh(mm);
        glDeleteTextures(2, tbo.data());
        glDeleteBuffers(2, buf.data());
        glDeleteTextures(static_cast<GLsizei>(tex.size()), tex.data());
    }};
    auto texture = [&](int tw, int th, GLenum internal, GLenum format, GLenum type,
                       const void* data) {
        tex.push_back(make_texture(tw, th, internal, format, type, data));
        return tex.back();
    };
    const GLuint t_z = texture(W, H, GL_R32F, GL_RED, GL_FLOAT, fz.data());
    const GLuint t_t = texture(W, H, GL_R32F, GL_RED, GL_FLOAT, ft.data());
    const GLuint t_shape = texture(W, H, GL_R32I, GL_RED_INTEGER, GL_INT, fshape.data());
    const GLuint t_tri = texture(W, H, GL_R32I, GL_RED_INTEGER, GL_INT, ftri.data());
    std::vector<float> nx(rays.ndc_x.begin(), rays.ndc_x.end()),
        ny(rays.ndc_y.begin(), rays.ndc_y.end());
    const GLuint t_nx = texture(W, 1, GL_R32F, GL_RED, GL_FLOAT, nx.data());
    const GLuint t_ny = texture(H, 1, GL_R32F, GL_RED, GL_FLOAT, ny.data());
    // Facet normals (TriangleMesh::facet_normal, double, then rounded as the G-buffer holds
    // them), per shape its first facet and material.
    std::vector<float> facets;
    std::vector<std::int32_t> shape_info;
    for (const SceneShape& s : scene.shapes) {
        shape_info.push_back(static_cast<std::int32_t>(facets.size() / 3));
        shape_info.push_back(s.material);
        for (size_t tri = 0; tri < s.mesh.triangles.size(); ++tri) {
            const Vec3 n = s.mesh.facet_normal(tri);
            facets.insert(facets.end(), {static_cast<float>(n.x), static_cast<float>(n.y),
                                         static_cast<float>(n.z)});
        }
    }
    if (facets.empty()) facets.assign(3, 0.f);
    if (shape_info.empty()) shape_info.assign(2, 0);
    glGenBuffers(2, buf.data());
    glBindBuffer(GL_TEXTURE_BUFFER, buf[0]);
    glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(facets.size() * sizeof(float)),
                 facets.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_TEXTURE_BUFFER, buf[1]);
    glBufferData(GL_TEXTURE_BUFFER,
                 static_cast<GLsizeiptr>(shape_info.size() * sizeof(std::int32_t)),
                 shape_info.data(), GL_STATIC_DRAW);
    glGenTextures(2, tbo.data());
    glBindTexture(GL_TEXTURE_BUFFER, tbo[0]);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGB32F, buf[0]);
    glBindTexture(GL_TEXTURE_BUFFER, tbo[1]);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RG32I, buf[1]);
    // Materials: row 0 (eta, alpha, c, medium), row 1 (albedo / pi, slab entries); the GGX
    // tables as the CPU interpolates them (BoundaryTransmittance at its own cosines); the slab
    // tables.
    const int M = std::max<int>(1, static_cast<int>(scene.materials.size()));
    const int C = o.transmittance_cosines;
    size_t slab_max = 1;
    for (const SlabTransmittance& s : slabs)
        slab_max = std::max(slab_max, std::min(s.thickness_mm.size(), s.transmittance.size()));
    std::vector<float> mat(static_cast<size_t>(8 * M), 0.f), bt(static_cast<size_t>(C * M), 0.f),
        slab(4 * slab_max * static_cast<size_t>(M), 0.f);
    for (size_t k = 0; k < scene.materials.size(); ++k) {
        const SceneMaterial& sm = scene.materials[k];
        float* r0 = &mat[4 * k];
        float* r1 = &mat[4 * (static_cast<size_t>(M) + k)];
        for (size_t c = 0; c < 3; ++c) r1[c] = static_cast<float>(sm.albedo[c] / std::numbers::pi);
        if (sm.kind != SceneMaterial::Kind::kMedium) continue;
        const auto [eta, alpha] = sm.boundary();
        const BoundaryTransmittance& T =
            tabulated_boundary(eta, alpha, o.transmittance_cosines, o.transmittance_quadrature);
        r0[0] = static_cast<float>(T.eta());
        r0[1] = static_cast<float>(T.alpha());
        r0[2] = static_cast<float>(T.hemispherical());
        r0[3] = 1.f;
        for (int c = 0; c < C; ++c)
            bt[k * static_cast<size_t>(C) + static_cast<size_t>(c)] =
                static_cast<float>(T(static_cast<double>(c) / (C - 1)));
        if (k < slabs.size()) {
            const SlabTransmittance& s = slabs[k];
            const size_t n = std::min(s.thickness_mm.size(), s.transmittance.size());
            if (s.empty()) continue;
            r1[3] = static_cast<float>(n);
            for (size_t e = 0; e < n; ++e) {
                float* q = &slab[4 * (k * slab_max + e)];
                q[0] = static_cast<float>(s.thickness_mm[e]);
                for (size_t c = 0; c < 3; ++c) q[1 + c] = static_cast<float>(s.transmittance[e][c]);
            }
        }
    }
    const GLuint t_mat = texture(M, 2, GL_RGBA32F, GL_RGBA, GL_FLOAT, mat.data());
    const GLuint t_bt = texture(C, M, GL_R32F, GL_RED, GL_FLOAT, bt.data());
    const GLuint t_slab =
        texture(static_cast<int>(slab_max), M, GL_RGBA32F, GL_RGBA, GL_FLOAT, slab.data());
    const bool any_slab = any_slab_table(slabs);
    // The meshes, positions relative to the camera.
    for (const SceneShape& s : scene.shapes) {
        std::vector<float> v(3 * s.mesh.positions.size());
        for (size_t i = 0; i < s.mesh.positions.size(); ++i) {
            const Vec3 d = s.mesh.positions[i] - cam;
            v[3 * i] = static_cast<float>(d.x);
            v[3 * i + 1] = static_cast<float>(d.y);
            v[3 * i + 2] = static_cast<float>(d.z);
        }
        meshes.push_back(upload_mesh(m.vao, v, s.mesh.triangles));
    }
    m.gbuffer_targets(W, H);
    check_gl("GlLighting upload");
    t.upload_ms = ms_since(t0);

    // What both lighting programs read.
    // What both lighting programs read (p made current), on texture units 0-5; returns the
    // first free unit.
    auto bind_common = [&](GLuint p) {
        glUseProgram(p);
        int unit = 0;
        bind_texture(p, "u_view_z", unit++, t_z);
        bind_texture(p, "u_shape", unit++, t_shape);
        bind_texture(p, "u_ndc_x", unit++, t_nx);
        bind_texture(p, "u_ndc_y", unit++, t_ny);
        bind_texture(p, "u_mat", unit++, t_mat);
        bind_texture(p, "u_boundary", unit++, t_bt);
        set(p, "u_forward", rays.forward);
        set(p, "u_right", rays.right);
        set(p, "u_up", rays.up);
        set_int(p, "u_height", H);
        set_int(p, "u_cosines", C);
        int ks = 0, kn = 0;
        Vec3 env{};
        for (size_t li = 0; li < lights.size(); ++li) {
            const Light& l = lights[li];
            const std::string k = std::to_string(ks), n = std::to_string(kn);
            Vec3 axis;
            double cos_half = 0;
            if (l.has_surface()) {
                const Vec3 c = l.pos - cam;
                glUniform4f(glGetUniformLocation(p, ("u_sphere[" + k + "]").c_str()),
                            static_cast<float>(c.x), static_cast<float>(c.y),
                            static_cast<float>(c.z), static_cast<float>(l.radius));
                set(p, ("u_sphere_color[" + k + "]").c_str(), l.L);
                set_int(p, ("u_sphere_light[" + k + "]").c_str(), static_cast<int>(li));
                ++ks;
            } else if (l.escape_cone(axis, cos_half) && cos_half <= -1) {
                env = env + Vec3{l.L[0], l.L[1], l.L[2]};
            } else if (l.escape_cone(axis, cos_half)) {
                glUniform4f(glGetUniformLocation(p, ("u_sun[" + n + "]").c_str()),
                            static_cast<float>(axis.x), static_cast<float>(axis.y),
                            static_cast<float>(axis.z), static_cast<float>(cos_half));
                set(p, ("u_sun_radiance[" + n + "]").c_str(), Vec3{l.L[0], l.L[1], l.L[2]});
                ++kn;
            }
        }
        set_int(p, "u_spheres", ks);
        set_int(p, "u_suns", kn);
        set(p, "u_environment", env);
        return unit;
    };

    // ---- The receiver pass.
    glBindFramebuffer(GL_FRAMEBUFFER, m.fb.fbo);
    glViewport(0, 0, W, H);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    m.timer->begin();
    {
        int unit = bind_common(m.receiver);
        bind_texture(m.receiver, "u_facet", unit++, tbo[0], GL_TEXTURE_BUFFER);
        bind_texture(m.receiver, "u_shape_info", unit++, tbo[1], GL_TEXTURE_BUFFER);
        bind_texture(m.receiver, "u_ray_t", unit++, t_t);
        bind_texture(m.receiver, "u_triangle", unit++, t_tri);
        glBindVertexArray(m.vao);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    m.timer->end();
    t.shading_gpu_ms += m.timer->gpu_ms();
    t.shading_wall_ms += m.timer->wall_ms();
    check_gl("GlLighting receiver pass");

    // The receivers' box, from the kinds read back, in double as lighting.cpp grows it.
    t0 = std::chrono::steady_clock::now();
    std::vector<std::int32_t> kind(2 * N);
    glReadBuffer(GL_COLOR_ATTACHMENT5);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, W, H, GL_RG_INTEGER, GL_INT, kind.data());
    t.readback_ms += ms_since(t0);
    Box receivers;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            if (kind[2 * (static_cast<size_t>(H - 1 - y) * W + x)] != 0)
                receivers.add(cam +
                              rays.unnormalized(x, y) * frame.view_z[frame.sample_index(x, y)]);

    // ---- Light samples: shadow maps and light passes, in the CPU's order. The light program's
    // inputs are set as often as they change: per frame here, per sample and per view below
    // (uniforms stay with a program and texture units with the context; the shadow maps'
    // program reads no texture).
    const GLuint p = m.light;
    int unit = bind_common(p);
    bind_texture(p, "u_normal", unit++, m.targets[4]);
    bind_texture(p, "u_kind", unit++, m.targets[5]);
    bind_texture(p, "u_slab", unit++, t_slab);
    const int map_unit = unit;
    set(p, "u_unit_mm", scene.unit_mm);
    set_int(p, "u_shadows", o.shadows);
    set(p, "u_normal_offset", o.normal_offset_texels);
    set(p, "u_depth_bias", o.depth_bias_texels);
    const LightPlan plan = plan_lights(scene, receivers, o);
    for (const LightSample& s : plan.samples) {
        const std::vector<ShadowView> views = plan.views(s, o);
        if (views.empty()) continue;
        if (static_cast<int>(views.size()) > kMaxViews)
            throw std::logic_error("GlLighting: more views than cube faces");
        const bool need_map = o.shadows || s.thickness_view || any_slab;
        glUseProgram(p);
        set_int(p, "u_directional", s.directional);
        set_int(p, "u_lobe", s.lobe);
        set_int(p, "u_thickness_view", s.thickness_view);
        set_int(p, "u_lights", s.lights);
        set(p, "u_w", s.w);
        set(p, "u_pos_rel", s.pos - cam);
        set(p, "u_lobe_n", s.lobe_n);
        set(p, "u_lobe_scale", s.lobe_scale);
        set(p, "u_lobe_offset", s.lobe_offset);
        set_int(p, "u_lobe_squared", s.lobe_squared);
        set(p, "u_value", s.value);
        set_int(p, "u_light", s.light);
        set_int(p, "u_need_map", need_map);
        set_int(p, "u_views", static_cast<int>(views.size()));
        for (size_t k = 0; k < views.size(); ++k) {
            const ShadowView::Projection pk = views[k].projection();
            const int ki = static_cast<int>(k);
            set_at(p, "u_origin_rel", ki, views[k].origin - cam);
            set_at(p, "u_px", ki, pk.x);
            set_at(p, "u_py", ki, pk.y);
            set_at(p, "u_pw", ki, pk.w);
        }
        for (size_t vi = 0; vi < views.size(); ++vi) {
            const ShadowView& v = views[vi];
            const ShadowTargets& st = m.shadow_targets(v.size);
            if (need_map) {
                const ShadowView::Projection proj = v.projection();
                // Depth range of an orthographic map: the casters' farthest corner.
                double range = 0;
                for (const Vec3& c : plan.casters.corners())
                    range = std::max(range, dot(c - v.origin, v.forward));
                glBindFramebuffer(GL_FRAMEBUFFER, st.fb.fbo);
                glViewport(0, 0, v.size, v.size);
                m.timer->begin();
                begin_id_pass(1);
                glUseProgram(m.shadow);
                set(m.shadow, "u_origin_rel", v.origin - cam);
                set(m.shadow, "u_px", proj.x);
                set(m.shadow, "u_py", proj.y);
                set(m.shadow, "u_pw", proj.w);
                set_int(m.shadow, "u_ortho", v.orthographic ? 1 : 0);
                set(m.shadow, "u_near", v.near);
                set(m.shadow, "u_inv_range", 1.0 / (range * (1 + 1e-4) + 1e-30));
                const GLint shape_loc = glGetUniformLocation(m.shadow, "u_shape");
                glBindVertexArray(m.vao);
                for (size_t k = 0; k < meshes.size(); ++k) {
                    glUniform1i(shape_loc, static_cast<GLint>(k));
                    draw_mesh(meshes[k], 3);
                }
                m.timer->end();
                end_id_pass();
                t.shadow_gpu_ms += m.timer->gpu_ms();
                t.shadow_wall_ms += m.timer->wall_ms();
                ++t.shadow_maps;
                check_gl("GlLighting shadow map");
            }
            // The light pass of this view.
            glBindFramebuffer(GL_FRAMEBUFFER, m.fb_light.fbo);
            glViewport(0, 0, W, H);
            glEnable(GL_BLEND);
            glBlendEquation(GL_FUNC_ADD);
            glBlendFunc(GL_ONE, GL_ONE);
            m.timer->begin();
            glUseProgram(p);
            bind_texture(p, "u_map_depth", map_unit, st.depth);
            bind_texture(p, "u_map_shape", map_unit + 1, st.shape);
            set_int(p, "u_view", static_cast<int>(vi));
            set_int(p, "u_ortho", v.orthographic);
            set(p, "u_near", v.near);
            set(p, "u_texel", v.texel_size(1.0));  // per unit depth (perspective)
            set_int(p, "u_size", v.size);
            glBindVertexArray(m.vao);
            glDrawArrays(GL_TRIANGLES, 0, 3);
            m.timer->end();
            glDisable(GL_BLEND);
            t.shading_gpu_ms += m.timer->gpu_ms();
            t.shading_wall_ms += m.timer->wall_ms();
            check_gl("GlLighting light pass");
        }
    }

    // ---- Read back into the G-buffer (rows flipped back).
    t0 = std::chrono::steady_clock::now();
    std::array<std::vector<float>, 5> layer;
    glBindFramebuffer(GL_FRAMEBUFFER, m.fb.fbo);
    for (int k = 0; k < 5; ++k) {
        layer[static_cast<size_t>(k)].resize(4 * N);
        glReadBuffer(static_cast<GLenum>(GL_COLOR_ATTACHMENT0 + k));
        glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, layer[static_cast<size_t>(k)].data());
    }
    check_gl("GlLighting read-back");
    t.readback_ms += ms_since(t0);
    g.resize(W, H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t i = frame.sample_index(x, y);
            const size_t gi = static_cast<size_t>(H - 1 - y) * W + x;
            g.view_z[i] = static_cast<float>(frame.view_z[i]);
            g.ray_t[i] = static_cast<float>(frame.ray_t[i]);
            g.shape[i] = frame.shape[i];
            g.material[i] = kind[2 * gi + 1];
            for (size_t c = 0; c < 3; ++c) {
                g.irradiance[3 * i + c] = layer[0][4 * gi + c];
                g.specular[3 * i + c] = layer[1][4 * gi + c];
                g.surface[3 * i + c] = layer[2][4 * gi + c];
                g.translucency[3 * i + c] = layer[3][4 * gi + c];
                g.normal[3 * i + c] = layer[4][4 * gi + c];
            }
            g.thickness[i] = layer[3][4 * gi + 3];
            g.exit_weight[i] = layer[4][4 * gi + 3];
        }

    t.wall_ms = ms_since(t_start);
    if (stats) {
        stats->shadow_maps = t.shadow_maps;
        stats->light_samples = static_cast<int>(plan.samples.size());
        stats->shadow_ms = t.shadow_wall_ms;
        stats->shading_ms = t.wall_ms - t.shadow_wall_ms;
    }
    if (times) *times = t;
}

}  // namespace ssslab::realtime::gl
