#include "realtime/gl/lighting_gl.h"

#include "realtime/gl/gl_util.h"
#include "realtime/gl/shaders.h"
#include "realtime/shadow_map.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

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

// What one GlLighting::shade call uploads, released on every exit (an exception in a later pass
// included): the frame's textures, the facets and shapes as texture buffers, the materials'
// tables and the meshes for the shadow maps.
struct ShadeUploads {
    std::vector<GLuint> tex;
    std::array<GLuint, 2> buf{}, tbo{};  // facets and shape_info: buffers, their textures
    std::vector<GlMesh> meshes;
    GLuint t_z = 0, t_t = 0, t_shape = 0, t_tri = 0, t_nx = 0, t_ny = 0;  // the frame, its rays
    GLuint t_mat = 0, t_bt = 0, t_slab = 0;                               // the materials
    ShadeUploads() = default;
    ShadeUploads(const ShadeUploads&) = delete;
    ShadeUploads& operator=(const ShadeUploads&) = delete;
    ~ShadeUploads() {
        for (const GlMesh& mm : meshes) release_mesh(mm);
        glDeleteTextures(2, tbo.data());
        glDeleteBuffers(2, buf.data());
        glDeleteTextures(static_cast<GLsizei>(tex.size()), tex.data());
    }
    // A texture made from `data`, released with the others.
    GLuint texture(int tw, int th, GLenum internal, GLenum format, GLenum type, const void* data) {
        tex.push_back(make_texture(tw, th, internal, format, type, data));
        return tex.back();
    }
};

// One GlLighting::shade call: its inputs, the sample grid and its camera rays, what it uploaded
// and the times of its passes.
struct ShadeCall {
    const Scene& scene;
    const RasterFrame& frame;
    const LightingOptions& o;
    const int W, H;
    const size_t N;
    const RasterCamera::SampleRays rays;
    const Vec3 cam;
    const int C;  // cosines of the boundary tables
    ShadeUploads up;
    GlLightingTimes t;

    ShadeCall(const Scene& scene_, const RasterCamera& camera, const RasterFrame& frame_,
              const LightingOptions& o_)
        : scene(scene_),
          frame(frame_),
          o(o_),
          W(frame_.sample_width()),
          H(frame_.sample_height()),
          N(static_cast<size_t>(W) * static_cast<size_t>(H)),
          rays(camera.sample_rays(frame_.supersample)),
          cam(camera.position),
          C(o_.transmittance_cosines) {}
};

// What camera and reflection rays see of the lights, as uniforms: their surfaces (spheres),
// the cones escaping rays see them in (suns' discs) and the environment (the whole sphere);
// std::invalid_argument for more than the programs take.
void check_light_counts(const std::vector<Light>& lights) {
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
}

// The G-buffer's geometry (GL rows: the frame's last row first) and the camera's rays.
void upload_frame(ShadeCall& c) {
    const int W = c.W, H = c.H;
    const RasterFrame& frame = c.frame;
    std::vector<float> fz(c.N), ft(c.N);
    std::vector<std::int32_t> fshape(c.N), ftri(c.N);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t k = frame.sample_index(x, y);
            const size_t gi = static_cast<size_t>(H - 1 - y) * W + x;
            fz[gi] = static_cast<float>(frame.view_z[k]);
            ft[gi] = static_cast<float>(frame.ray_t[k]);
            fshape[gi] = frame.shape[k];
            ftri[gi] = frame.shape[k] >= 0 ? static_cast<std::int32_t>(frame.triangle[k]) : 0;
        }
    ShadeUploads& u = c.up;
    u.t_z = u.texture(W, H, GL_R32F, GL_RED, GL_FLOAT, fz.data());
    u.t_t = u.texture(W, H, GL_R32F, GL_RED, GL_FLOAT, ft.data());
    u.t_shape = u.texture(W, H, GL_R32I, GL_RED_INTEGER, GL_INT, fshape.data());
    u.t_tri = u.texture(W, H, GL_R32I, GL_RED_INTEGER, GL_INT, ftri.data());
    std::vector<float> nx(c.rays.ndc_x.begin(), c.rays.ndc_x.end()),
        ny(c.rays.ndc_y.begin(), c.rays.ndc_y.end());
    u.t_nx = u.texture(W, 1, GL_R32F, GL_RED, GL_FLOAT, nx.data());
    u.t_ny = u.texture(H, 1, GL_R32F, GL_RED, GL_FLOAT, ny.data());
}

// Facet normals (TriangleMesh::facet_normal, double, then rounded as the G-buffer holds
// them), per shape its first facet and material.
void upload_facets(ShadeCall& c) {
    std::vector<float> facets;
    std::vector<std::int32_t> shape_info;
    for (const SceneShape& s : c.scene.shapes) {
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
    ShadeUploads& u = c.up;
    glGenBuffers(2, u.buf.data());
    glBindBuffer(GL_TEXTURE_BUFFER, u.buf[0]);
    glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(facets.size() * sizeof(float)),
                 facets.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_TEXTURE_BUFFER, u.buf[1]);
    glBufferData(GL_TEXTURE_BUFFER,
                 static_cast<GLsizeiptr>(shape_info.size() * sizeof(std::int32_t)),
                 shape_info.data(), GL_STATIC_DRAW);
    glGenTextures(2, u.tbo.data());
    glBindTexture(GL_TEXTURE_BUFFER, u.tbo[0]);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGB32F, u.buf[0]);
    glBindTexture(GL_TEXTURE_BUFFER, u.tbo[1]);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RG32I, u.buf[1]);
}

// Materials: row 0 (eta, alpha, c, medium), row 1 (albedo / pi, slab entries); the GGX
// tables as the CPU interpolates them (BoundaryTransmittance at its own cosines); the slab
// tables.
void upload_materials(ShadeCall& c, const std::vector<SlabTransmittance>& slabs) {
    const Scene& scene = c.scene;
    const LightingOptions& o = c.o;
    const int M = std::max<int>(1, static_cast<int>(scene.materials.size()));
    const int C = c.C;
    size_t slab_max = 1;
    for (const SlabTransmittance& s : slabs)
        slab_max = std::max(slab_max, std::min(s.thickness_mm.size(), s.transmittance.size()));
    std::vector<float> mat(static_cast<size_t>(8 * M), 0.f), bt(static_cast<size_t>(C * M), 0.f),
        slab(4 * slab_max * static_cast<size_t>(M), 0.f);
    for (size_t k = 0; k < scene.materials.size(); ++k) {
        const SceneMaterial& sm = scene.materials[k];
        float* r0 = &mat[4 * k];
        float* r1 = &mat[4 * (static_cast<size_t>(M) + k)];
        for (size_t ch = 0; ch < 3; ++ch)
            r1[ch] = static_cast<float>(sm.albedo[ch] / std::numbers::pi);
        if (sm.kind != SceneMaterial::Kind::kMedium) continue;
        const auto [eta, alpha] = sm.boundary();
        const BoundaryTransmittance& T =
            tabulated_boundary(eta, alpha, o.transmittance_cosines, o.transmittance_quadrature);
        r0[0] = static_cast<float>(T.eta());
        r0[1] = static_cast<float>(T.alpha());
        r0[2] = static_cast<float>(T.hemispherical());
        r0[3] = 1.f;
        for (int ci = 0; ci < C; ++ci)
            bt[k * static_cast<size_t>(C) + static_cast<size_t>(ci)] =
                static_cast<float>(T(static_cast<double>(ci) / (C - 1)));
        if (k < slabs.size()) {
            const SlabTransmittance& s = slabs[k];
            const size_t n = std::min(s.thickness_mm.size(), s.transmittance.size());
            if (s.empty()) continue;
            r1[3] = static_cast<float>(n);
            for (size_t e = 0; e < n; ++e) {
                float* q = &slab[4 * (k * slab_max + e)];
                q[0] = static_cast<float>(s.thickness_mm[e]);
                for (size_t ch = 0; ch < 3; ++ch)
                    q[1 + ch] = static_cast<float>(s.transmittance[e][ch]);
            }
        }
    }
    ShadeUploads& u = c.up;
    u.t_mat = u.texture(M, 2, GL_RGBA32F, GL_RGBA, GL_FLOAT, mat.data());
    u.t_bt = u.texture(C, M, GL_R32F, GL_RED, GL_FLOAT, bt.data());
    u.t_slab = u.texture(static_cast<int>(slab_max), M, GL_RGBA32F, GL_RGBA, GL_FLOAT, slab.data());
}

// The meshes, positions relative to the camera.
void upload_meshes(ShadeCall& c, GLuint vao) {
    for (const SceneShape& s : c.scene.shapes) {
        std::vector<float> v(3 * s.mesh.positions.size());
        for (size_t i = 0; i < s.mesh.positions.size(); ++i) {
            const Vec3 d = s.mesh.positions[i] - c.cam;
            v[3 * i] = static_cast<float>(d.x);
            v[3 * i + 1] = static_cast<float>(d.y);
            v[3 * i + 2] = static_cast<float>(d.z);
        }
        c.up.meshes.push_back(upload_mesh(vao, v, s.mesh.triangles));
    }
}

// The lights as the lighting programs see them (p current): the sphere lights' surfaces, the
// suns' discs and the environment's radiance.
void set_light_uniforms(GLuint p, const std::vector<Light>& lights, const Vec3& cam) {
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
                        static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z),
                        static_cast<float>(l.radius));
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
}

// What both lighting programs read (p made current), on texture units 0-5; returns the
// first free unit.
int bind_common(GLuint p, const ShadeCall& c, const std::vector<Light>& lights) {
    glUseProgram(p);
    int unit = 0;
    bind_texture(p, "u_view_z", unit++, c.up.t_z);
    bind_texture(p, "u_shape", unit++, c.up.t_shape);
    bind_texture(p, "u_ndc_x", unit++, c.up.t_nx);
    bind_texture(p, "u_ndc_y", unit++, c.up.t_ny);
    bind_texture(p, "u_mat", unit++, c.up.t_mat);
    bind_texture(p, "u_boundary", unit++, c.up.t_bt);
    set(p, "u_forward", c.rays.forward);
    set(p, "u_right", c.rays.right);
    set(p, "u_up", c.rays.up);
    set_int(p, "u_height", c.H);
    set_int(p, "u_cosines", c.C);
    set_light_uniforms(p, lights, c.cam);
    return unit;
}

// A light sample's inputs of the light program (p current), and its views' projections.
void set_sample_uniforms(GLuint p, const LightSample& s, const std::vector<ShadowView>& views,
                         bool need_map, const Vec3& cam) {
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
}

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

    // ---- The passes of one shade call, in order.

    // The receiver pass: one full-screen draw into the six targets.
    void receiver_pass(ShadeCall& c, const std::vector<Light>& lights) {
        glBindFramebuffer(GL_FRAMEBUFFER, fb.fbo);
        glViewport(0, 0, c.W, c.H);
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glDisable(GL_BLEND);
        timer->begin();
        {
            int unit = bind_common(receiver, c, lights);
            bind_texture(receiver, "u_facet", unit++, c.up.tbo[0], GL_TEXTURE_BUFFER);
            bind_texture(receiver, "u_shape_info", unit++, c.up.tbo[1], GL_TEXTURE_BUFFER);
            bind_texture(receiver, "u_ray_t", unit++, c.up.t_t);
            bind_texture(receiver, "u_triangle", unit++, c.up.t_tri);
            glBindVertexArray(vao);
            glDrawArrays(GL_TRIANGLES, 0, 3);
        }
        timer->end();
        c.t.shading_gpu_ms += timer->gpu_ms();
        c.t.shading_wall_ms += timer->wall_ms();
        check_gl("GlLighting receiver pass");
    }

    // The receivers' kinds and materials read back into `kind` (GL rows, 2 a sample), and the
    // receivers' box from the kinds, in double as lighting.cpp grows it.
    Box read_receivers(ShadeCall& c, std::vector<std::int32_t>& kind) {
        const int W = c.W, H = c.H;
        const auto t0 = std::chrono::steady_clock::now();
        kind.assign(2 * c.N, 0);
        glReadBuffer(GL_COLOR_ATTACHMENT5);
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        glReadPixels(0, 0, W, H, GL_RG_INTEGER, GL_INT, kind.data());
        c.t.readback_ms += ms_since(t0);
        Box receivers;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                if (kind[2 * (static_cast<size_t>(H - 1 - y) * W + x)] != 0)
                    receivers.add(c.cam + c.rays.unnormalized(x, y) *
                                              c.frame.view_z[c.frame.sample_index(x, y)]);
        return receivers;
    }

    // The light program's inputs that stay for the frame (see light_samples); returns the
    // texture unit of the shadow map's depth (its shapes on the next).
    int set_up_light_program(ShadeCall& c, const std::vector<Light>& lights) {
        const GLuint p = light;
        int unit = bind_common(p, c, lights);
        bind_texture(p, "u_normal", unit++, targets[4]);
        bind_texture(p, "u_kind", unit++, targets[5]);
        bind_texture(p, "u_slab", unit++, c.up.t_slab);
        const int map_unit = unit;
        set(p, "u_unit_mm", c.scene.unit_mm);
        set_int(p, "u_shadows", c.o.shadows);
        set(p, "u_normal_offset", c.o.normal_offset_texels);
        set(p, "u_depth_bias", c.o.depth_bias_texels);
        return map_unit;
    }

    // The shadow map of view v into st: the scene's shapes from the light, their depth range
    // that of the casters' box.
    void draw_shadow_map(ShadeCall& c, const ShadowView& v, const ShadowTargets& st,
                         const Box& casters) {
        const ShadowView::Projection proj = v.projection();
        // Depth range of an orthographic map: the casters' farthest corner.
        double range = 0;
        for (const Vec3& k : casters.corners())
            range = std::max(range, dot(k - v.origin, v.forward));
        glBindFramebuffer(GL_FRAMEBUFFER, st.fb.fbo);
        glViewport(0, 0, v.size, v.size);
        timer->begin();
        begin_id_pass(1);
        glUseProgram(shadow);
        set(shadow, "u_origin_rel", v.origin - c.cam);
        set(shadow, "u_px", proj.x);
        set(shadow, "u_py", proj.y);
        set(shadow, "u_pw", proj.w);
        set_int(shadow, "u_ortho", v.orthographic ? 1 : 0);
        set(shadow, "u_near", v.near);
        set(shadow, "u_inv_range", 1.0 / (range * (1 + 1e-4) + 1e-30));
        const GLint shape_loc = glGetUniformLocation(shadow, "u_shape");
        glBindVertexArray(vao);
        for (size_t k = 0; k < c.up.meshes.size(); ++k) {
            glUniform1i(shape_loc, static_cast<GLint>(k));
            draw_mesh(c.up.meshes[k], 3);
        }
        timer->end();
        end_id_pass();
        c.t.shadow_gpu_ms += timer->gpu_ms();
        c.t.shadow_wall_ms += timer->wall_ms();
        ++c.t.shadow_maps;
        check_gl("GlLighting shadow map");
    }

    // The light pass of view vi (v) of the current light sample, its map in st: blended into
    // the four lighting targets.
    void draw_light_view(ShadeCall& c, const ShadowView& v, size_t vi, const ShadowTargets& st,
                         int map_unit) {
        const GLuint p = light;
        glBindFramebuffer(GL_FRAMEBUFFER, fb_light.fbo);
        glViewport(0, 0, c.W, c.H);
        glEnable(GL_BLEND);
        glBlendEquation(GL_FUNC_ADD);
        glBlendFunc(GL_ONE, GL_ONE);
        timer->begin();
        glUseProgram(p);
        bind_texture(p, "u_map_depth", map_unit, st.depth);
        bind_texture(p, "u_map_shape", map_unit + 1, st.shape);
        set_int(p, "u_view", static_cast<int>(vi));
        set_int(p, "u_ortho", v.orthographic);
        set(p, "u_near", v.near);
        set(p, "u_texel", v.texel_size(1.0));  // per unit depth (perspective)
        set_int(p, "u_size", v.size);
        glBindVertexArray(vao);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        timer->end();
        glDisable(GL_BLEND);
        c.t.shading_gpu_ms += timer->gpu_ms();
        c.t.shading_wall_ms += timer->wall_ms();
        check_gl("GlLighting light pass");
    }

    // Light samples: shadow maps and light passes, in the CPU's order. The light program's
    // inputs are set as often as they change: per frame (set_up_light_program), per sample and
    // per view here (uniforms stay with a program and texture units with the context; the
    // shadow maps' program reads no texture).
    void light_samples(ShadeCall& c, const LightPlan& plan, int map_unit, bool any_slab) {
        for (const LightSample& s : plan.samples) {
            const std::vector<ShadowView> views = plan.views(s, c.o);
            if (views.empty()) continue;
            if (static_cast<int>(views.size()) > kMaxViews)
                throw std::logic_error("GlLighting: more views than cube faces");
            const bool need_map = c.o.shadows || s.thickness_view || any_slab;
            glUseProgram(light);
            set_sample_uniforms(light, s, views, need_map, c.cam);
            for (size_t vi = 0; vi < views.size(); ++vi) {
                const ShadowView& v = views[vi];
                const ShadowTargets& st = shadow_targets(v.size);
                if (need_map) draw_shadow_map(c, v, st, plan.casters);
                draw_light_view(c, v, vi, st, map_unit);
            }
        }
    }

    // Read back into the G-buffer (rows flipped back); `kind` as read_receivers read it.
    void read_back(ShadeCall& c, const std::vector<std::int32_t>& kind, GBuffer& g) {
        const int W = c.W, H = c.H;
        const size_t N = c.N;
        const RasterFrame& frame = c.frame;
        const auto t0 = std::chrono::steady_clock::now();
        std::array<std::vector<float>, 5> layer;
        glBindFramebuffer(GL_FRAMEBUFFER, fb.fbo);
        for (int k = 0; k < 5; ++k) {
            layer[static_cast<size_t>(k)].resize(4 * N);
            glReadBuffer(static_cast<GLenum>(GL_COLOR_ATTACHMENT0 + k));
            glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, layer[static_cast<size_t>(k)].data());
        }
        check_gl("GlLighting read-back");
        c.t.readback_ms += ms_since(t0);
        g.resize(W, H);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const size_t i = frame.sample_index(x, y);
                const size_t gi = static_cast<size_t>(H - 1 - y) * W + x;
                g.view_z[i] = static_cast<float>(frame.view_z[i]);
                g.ray_t[i] = static_cast<float>(frame.ray_t[i]);
                g.shape[i] = frame.shape[i];
                g.material[i] = kind[2 * gi + 1];
                for (size_t ch = 0; ch < 3; ++ch) {
                    g.irradiance[3 * i + ch] = layer[0][4 * gi + ch];
                    g.specular[3 * i + ch] = layer[1][4 * gi + ch];
                    g.surface[3 * i + ch] = layer[2][4 * gi + ch];
                    g.translucency[3 * i + ch] = layer[3][4 * gi + ch];
                    g.normal[3 * i + ch] = layer[4][4 * gi + ch];
                }
                g.thickness[i] = layer[3][4 * gi + 3];
                g.exit_weight[i] = layer[4][4 * gi + 3];
            }
    }
};

GlLighting::GlLighting(GlContext& context) : impl_(std::make_unique<Impl>(context)) {}
GlLighting::~GlLighting() = default;

void GlLighting::shade(const Scene& scene, const RasterCamera& camera, const RasterFrame& frame,
                       const LightingOptions& o, const std::vector<SlabTransmittance>& slabs,
                       LightingStats* stats, GBuffer& g, GlLightingTimes* times) {
    const auto t_start = std::chrono::steady_clock::now();
    check_lighting_inputs(camera, frame, o);
    // The scene's lights resolved once (core/light.h): the receiver pass's, then the plan's
    // (LightPlan::lights) for the light passes.
    std::vector<Light> lights(scene.lights.begin(), scene.lights.end());
    check_light_counts(lights);
    Impl& m = *impl_;
    m.ctx.make_current();
    ShadeCall c(scene, camera, frame, o);

    // ---- Uploads: the G-buffer's geometry, the camera's rays, facets, materials and their
    // tables, the meshes for the shadow maps (released with `c` on every exit).
    const auto t0 = std::chrono::steady_clock::now();
    upload_frame(c);
    upload_facets(c);
    upload_materials(c, slabs);
    upload_meshes(c, m.vao);
    m.gbuffer_targets(c.W, c.H);
    check_gl("GlLighting upload");
    c.t.upload_ms = ms_since(t0);

    m.receiver_pass(c, lights);
    std::vector<std::int32_t> kind;
    const Box receivers = m.read_receivers(c, kind);
    const LightPlan plan = plan_lights(scene, receivers, o, std::move(lights));
    const int map_unit = m.set_up_light_program(c, plan.lights);
    m.light_samples(c, plan, map_unit, any_slab_table(slabs));
    m.read_back(c, kind, g);

    c.t.wall_ms = ms_since(t_start);
    if (stats) {
        stats->shadow_maps = c.t.shadow_maps;
        stats->light_samples = static_cast<int>(plan.samples.size());
        stats->shadow_ms = c.t.shadow_wall_ms;
        stats->shading_ms = c.t.wall_ms - c.t.shadow_wall_ms;
    }
    if (times) *times = c.t;
}

}  // namespace ssslab::realtime::gl
