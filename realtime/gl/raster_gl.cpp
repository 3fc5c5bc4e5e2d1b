#include "realtime/gl/raster_gl.h"

#include "core/mesh.h"
#include "realtime/gl/gl_util.h"
#include "realtime/gl/shaders.h"

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

namespace ssslab::realtime::gl {

struct GlRaster::Impl {
    GlContext& ctx;
    GLuint program = 0, vao = 0;
    std::unique_ptr<GlTimer> timer;
    GLuint tex_z = 0, tex_shape = 0, tex_tri = 0;
    GlFramebuffer fb;
    int w = 0, h = 0;

    explicit Impl(GlContext& c) : ctx(c) {
        ctx.make_current();
        require_gl(4, 5, "the GL raster needs OpenGL 4.5 (glClipControl)");
        program = link_program(shaders::raster_vert, shaders::raster_frag,
                               "realtime/gl/shaders/raster.{vert,frag}");
        glGenVertexArrays(1, &vao);
        timer = std::make_unique<GlTimer>();
        check_gl("GlRaster set-up");
    }
    ~Impl() {
        ctx.make_current();
        release_targets();
        timer.reset();
        glDeleteVertexArrays(1, &vao);
        glDeleteProgram(program);
    }
    void release_targets() {
        const GLuint t[] = {tex_z, tex_shape, tex_tri};
        glDeleteTextures(3, t);
        release_framebuffer(fb);
        fb = {};
        tex_z = tex_shape = tex_tri = 0;
        w = h = 0;
    }
    // The render targets at width x height (kept while the size is unchanged).
    void targets(int width, int height) {
        if (width == w && height == h) return;
        release_targets();
        w = width;
        h = height;
        tex_z = make_texture(w, h, GL_R32F, GL_RED, GL_FLOAT, nullptr);
        tex_shape = make_texture(w, h, GL_R32I, GL_RED_INTEGER, GL_INT, nullptr);
        tex_tri = make_texture(w, h, GL_R32I, GL_RED_INTEGER, GL_INT, nullptr);
        fb = make_framebuffer(w, h, {tex_z, tex_shape, tex_tri}, true, "GlRaster's G-buffer");
    }
};

GlRaster::GlRaster(GlContext& context) : impl_(std::make_unique<Impl>(context)) {}
GlRaster::~GlRaster() = default;

void GlRaster::rasterize(const Scene& scene, const RasterOptions& o, int width, int height,
                         RasterFrame& f, GlRasterTimes* times) {
    const auto t0 = std::chrono::steady_clock::now();
    if (o.supersample < 1) throw std::invalid_argument("GlRaster: supersample must be >= 1");
    if (o.orthographic || !o.depth_test || o.on_tile || o.cull_front_closed)
        throw std::invalid_argument(
            "GlRaster: orthographic views, no depth test, tile "
            "callbacks and front-face culling are not supported");
    // Supersampled as the software rasterizer: the same field of view on a grid of s x s
    // samples a pixel (the clip coordinates do not depend on the grid), pixels box-filtered.
    const RasterCamera camera = RasterCamera::from_scene(scene.camera, width, height);
    const int ss = o.supersample;
    const int w = camera.width * ss, h = camera.height * ss;
    Impl& m = *impl_;
    m.ctx.make_current();
    m.targets(w, h);

    // The meshes: clip coordinates in double through the software rasterizer's projection,
    // uploaded as floats with z = near.
    struct Draw {
        GlMesh mesh;
        bool cull = false;
    };
    std::vector<Draw> draws;
    const float near = static_cast<float>(o.near);
    for (const SceneShape& s : scene.shapes) {
        const bool cull = o.cull_closed && (s.closed ? *s.closed : check_mesh(s.mesh).closed());
        const RasterMesh rm = project(camera, s.mesh, cull);
        std::vector<float> v(4 * rm.vertices.size());
        for (size_t i = 0; i < rm.vertices.size(); ++i) {
            v[4 * i] = static_cast<float>(rm.vertices[i].x);
            v[4 * i + 1] = static_cast<float>(rm.vertices[i].y);
            v[4 * i + 2] = near;
            v[4 * i + 3] = static_cast<float>(rm.vertices[i].w);
        }
        Draw d;
        d.cull = cull;
        d.mesh = upload_mesh(m.vao, v, s.mesh.triangles);
        draws.push_back(d);
    }
    check_gl("GlRaster upload");

    m.timer->begin();
    glBindFramebuffer(GL_FRAMEBUFFER, m.fb.fbo);
    glViewport(0, 0, w, h);
    begin_id_pass(2);
    glUseProgram(m.program);
    const GLint shape_loc = glGetUniformLocation(m.program, "u_shape");
    glFrontFace(GL_CCW);
    glCullFace(GL_BACK);
    glBindVertexArray(m.vao);
    for (size_t i = 0; i < draws.size(); ++i) {
        if (draws[i].cull)
            glEnable(GL_CULL_FACE);
        else
            glDisable(GL_CULL_FACE);
        glUniform1i(shape_loc, static_cast<GLint>(i));
        draw_mesh(draws[i].mesh, 4);
    }
    m.timer->end();
    end_id_pass();
    check_gl("GlRaster draw");

    // Read back, rows flipped (GL's window origin is the lower left, the frame's rows go down).
    const size_t n = static_cast<size_t>(w) * h;
    std::vector<float> z(n);
    std::vector<std::int32_t> shape(n), tri(n);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, w, h, GL_RED, GL_FLOAT, z.data());
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, w, h, GL_RED_INTEGER, GL_INT, shape.data());
    glReadBuffer(GL_COLOR_ATTACHMENT2);
    glReadPixels(0, 0, w, h, GL_RED_INTEGER, GL_INT, tri.data());
    check_gl("GlRaster read-back");
    for (const Draw& d : draws) release_mesh(d.mesh);

    f.width = camera.width;
    f.height = camera.height;
    f.supersample = ss;
    f.view_z.resize(n);
    f.ray_t.resize(n);
    f.shape.resize(n);
    f.triangle.resize(n);
    f.barycentric.clear();
    f.fragments.clear();
    const RasterCamera::SampleRays rays = camera.sample_rays(ss);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t k = f.sample_index(x, y);
            const size_t g = static_cast<size_t>(h - 1 - y) * w + x;
            const bool covered = shape[g] >= 0;
            f.shape[k] = shape[g];
            f.triangle[k] = covered ? static_cast<std::uint32_t>(tri[g])
                                    : std::numeric_limits<std::uint32_t>::max();
            f.view_z[k] =
                covered ? static_cast<double>(z[g]) : std::numeric_limits<double>::infinity();
            f.ray_t[k] = covered ? f.view_z[k] * rays.length_per_depth(x, y) : 0.0;
        }
    // The pixels as the software rasterizer filters them.
    if (o.pixel_layers) {
        resolve_pixel_layers(f);
    } else {
        f.coverage.clear();
        f.depth.clear();
    }
    if (times) {
        times->gpu_ms = m.timer->gpu_ms();
        times->draw_ms = m.timer->wall_ms();
        times->wall_ms = ms_since(t0);
    }
}

}  // namespace ssslab::realtime::gl
