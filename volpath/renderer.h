// The path tracer of volpath/render.cpp as a struct: what it holds of the scene (the Embree
// scene, the lights and the ones the guides aim at, the media and per shape which, the camera),
// the state of one camera path (CameraPath), and the declarations of its member functions. Their
// bodies: render.cpp (the constructor, shadow rays and NEE, the camera path, its surface
// vertices and the walk's hooks inside media) and render_guides.cpp (the exit guide at
// scattering vertices and at a rough boundary's own vertices, and the diffuse guide); the small
// ones a path calls at every vertex or collision, and reaches (every shadow ray, NEE's and the
// guides'), are defined here. Renderer is hidden outside the library, as it was in render.cpp's
// anonymous namespace: the calls between its functions stay direct, not through the PLT.
// Internal to the renderer: included by render.cpp and render_guides.cpp only.
#pragma once

#include "core/light.h"
#include "core/rng.h"
#include "core/scene.h"
#include "core/vec3.h"
#include "volpath/embree_scene.h"
#include "volpath/mesh_medium.h"
#include "volpath/render.h"
#include "volpath/render_guides.h"
#include "volpath/walk.h"

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace ssslab::volpath::render_detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct __attribute__((visibility("hidden"))) Renderer {
    const Scene& scene;
    const RenderOptions& opt;
    int width, height;
    std::unique_ptr<EmbreeScene> es;
    std::vector<Light> lights;
    std::vector<int> guide_lights;  // the lights exit guides aim at (exit_guide)
    std::vector<int> shape_medium;  // per shape: index into media, or -1 (diffuse)
    std::vector<MediumData> media;
    // Per shape of a medium (with skip_queries_in_balls): where its walks need no queries.
    std::vector<std::unique_ptr<SurfaceDistanceGrid>> shape_balls;
    double eps = 1e-6;
    bool has_passable = false;  // any index-matched homogeneous medium (shadow rays cross them)
    std::vector<char> passable_shape;  // per shape: a boundary shadow rays cross (passable())
    Vec3 cam_pos, cam_f, cam_r, cam_u;
    double tan_half = 0, aspect = 1;
    // The probability that NEE samples a given light: 1 when every light is sampled at every
    // vertex (RenderOptions::nee_all_lights), else 1 / lights (one chosen uniformly).
    double sel = 1;

    Renderer(const Scene& s, const RenderOptions& o);

    // The normal the environment is sampled about at a surface (null: the whole sphere).
    const Vec3* env_normal(const Vec3* surface_normal) const {
        return opt.environment_cosine ? surface_normal : nullptr;
    }

    // Whether shadow and path rays pass through medium mi's boundary unchanged: an
    // index-matched homogeneous medium (its transmittance is then known in closed form).
    bool passable(int mi) const {
        const MediumData& md = media[static_cast<size_t>(mi)];
        return opt.index_matched_nee && md.eta == 1.0 && !md.density;
    }

    // Shadow rays and NEE (render.cpp, but for reaches). Those declared inline are defined in
    // render.cpp, the one file that calls them: the keyword keeps the compiler's inlining of
    // them as it was in the class body (without it, ketchup's paths ran 1.2 % more instructions).
    bool shadow(const Vec3& o, const Vec3& wi, double tmax, int start_medium, RGB& T,
                std::uint64_t& rays, TriangleRef leaving) const;
    template <class F, class P>
    inline void nee(const Vec3& p, const SurfaceAt* at, RngStream& rng, const double* beta, F f_of,
                    P pdf_of, RGB& out, std::uint64_t& rays, int medium = -1,
                    const GuideShare& share = {}) const;
    template <class F, class P>
    inline void nee_light(const Light& light, const Vec3& p, const SurfaceAt* at, RngStream& rng,
                          const double* beta, F& f_of, P& pdf_of, RGB& out, std::uint64_t& rays,
                          int medium, const GuideShare& share) const;
    // Whether the shadow ray from p towards the light sample ls reaches the light (`at`: the
    // surface p lies on, or null inside medium `medium`); T: the transmittance of the
    // index-matched media it crosses.
    bool reaches(const Light& light, const Vec3& p, const SurfaceAt* at, const LightSample& ls,
                 int medium, RGB& T, std::uint64_t& rays) const {
        // From a surface: from the point itself, its triangle skipped and hits within
        // single-precision rounding of it (volpath-render-7), or (the option) eps off it along
        // the normal.
        const bool offset = at && !opt.rays_from_surface;
        const Vec3 o = offset ? p + at->n * eps : p;
        const TriangleRef leaving = at && !offset ? at->triangle : TriangleRef{};
        const double tmax = std::isfinite(ls.dist) ? ls.dist * (1 - 1e-7) - eps : kInf;
        // Sphere lights are opaque emitters outside the BVH: one in the way blocks the light
        // sampled (as it ends a path that meets it). Before volpath-render-4 the environment and
        // the sun were sampled through them, too bright by their MIS share of the sphere's
        // solid angle.
        for (const Light& other : lights)
            if (&other != &light && other.hit(o, ls.wi) < tmax) return false;
        T = {1, 1, 1};
        if (has_passable) return shadow(o, ls.wi, tmax, medium, T, rays, leaving);
        ++rays;
        return !es->occluded(o, ls.wi, 0, tmax, leaving);
    }
    inline void add_escape(const Vec3& from, const Vec3* from_normal, const Vec3& d, bool prev_nee,
                           double prev_pdf, const double* beta, RGB& out,
                           const GuideShare& share) const;

    // The hero mixture P(k) q_k of a walk that enters medium md now, with weights ws: the
    // probabilities the entry will choose the hero with (RenderHero::kThroughputAlbedo), else
    // the path's own; and of a walk that goes on inside.
    std::array<double, 3> entry_probabilities(const WalkState<3>& ws, const MediumData& md) const {
        if (opt.hero == RenderHero::kThroughputAlbedo)
            return ws.weights.throughput_probabilities(md.region.albedo);
        return inside_probabilities(ws);
    }
    static std::array<double, 3> inside_probabilities(const WalkState<3>& ws) {
        std::array<double, 3> pq{};
        for (std::size_t k = 0; k < 3; ++k) pq[k] = ws.weights.prob[k] * ws.weights.q[k];
        return pq;
    }

    // The state of one camera path (trace): position, direction and weights of the whole path
    // (ws), where it is, and what the MIS of its next hit needs of the vertex before.
    struct CameraPath {
        CameraPath(int hero_, RngStream& rng_, double* T_) : hero(hero_), rng(rng_), T(T_) {}
        int hero;
        RngStream& rng;
        double* T;  // the pixel's tally
        std::uint64_t rays = 0;
        WalkState<3> ws;  // position, direction, weights and events of the whole path
        // Outside media: the triangle the next ray leaves (rays_from_surface), else none.
        TriangleRef leave;
        int medium = -1;  // index into media of the medium the path is in
        int medium_shape = -1;
        bool prev_nee = false, entered = false, specular_path = false;
        double prev_pdf = 0;
        Vec3 nee_pos;     // where NEE was last done (MIS of a light hit found by sampling)
        Vec3 nee_normal;  // and there the normal of the lit side, if on a surface
        bool nee_on_surface = false;  // (the environment is sampled about it: Light::sample)
        int depth = 0;                // surface vertices (medium events do not count)
        ExitGuide guide;              // of the last vertex a walk went on from (exit_guide)
        bool guide_armed = false;     // it aims at the boundary the path meets next
        GuideShare exit_share;        // at the exit the path left by: its part in the next hit
        bool left_guided = false;     // the path has just left a guided medium (diffuse_guides)
        DiffuseGuide plate;           // of the last diffuse vertex (diffuse_guides)
        Vec3 plate_n;                 // and its normal
        bool plate_armed = false;     // it takes part in the entry the path meets next
    };

    // Adds a contribution of path c to its pixel's layers. `subsurface`: light that entered a
    // medium whatever the path so far (an exit guide's estimate at the boundary where the path is
    // still outside).
    static void flush(CameraPath& c, const RGB& contribution, bool subsurface = false) {
        for (int k = 0; k < 3; ++k) {
            const double v = contribution[static_cast<size_t>(k)];
            c.T[RenderLayout::kRadiance + k] += v;
            if (c.entered || subsurface)
                c.T[RenderLayout::kSubsurface + k] += v;
            else if (c.specular_path)
                c.T[RenderLayout::kSpecular + k] += v;
        }
    }

    // The next ray outside media leaves the surface at p (triangle tri) on the side of n: from p
    // itself, that triangle and hits within rounding skipped (volpath-render-7), or (the option)
    // from eps off it.
    void leave_outside(CameraPath& c, const Vec3& p, const Vec3& n, TriangleRef tri) const {
        c.ws.on_surface = false;
        if (opt.rays_from_surface) {
            c.ws.p = p;
            c.leave = tri;
        } else {
            c.ws.p = p + n * eps;
        }
    }

    // The guides (render_guides.cpp), but for run_exit_guide's coin, drawn at every scattering
    // vertex of a guided medium.
    void exit_guide(const MediumData& md, int shape, ExitGuide& g, std::uint64_t& rays) const;
    // The exit guide's estimator at g's vertex, run with probability kExitGuideProb (the one
    // ExitGuide::density counts): g aimed, its estimate added to out.
    void run_exit_guide(ExitGuide& g, const MediumData& md, int shape, const double* bs,
                        RngStream& rng, RGB& out, std::uint64_t& rays) const {
        if (!(rng.stream_uniform() < kExitGuideProb)) return;
        exit_guide(md, shape, g, rays);
        guided_exits(g, md, shape, bs, rng, out, rays);
    }
    void guided_exits(const ExitGuide& g, const MediumData& md, int shape, const double* bs,
                      RngStream& rng, RGB& out, std::uint64_t& rays) const;
    GuideShare arrival_share(CameraPath& c, const Vec3& p, const MediumData& md) const;
    bool boundary_guide(CameraPath& c, const Vec3& p, const Vec3& n, TriangleRef tri,
                        const MediumData& md, bool outside, bool plate_arrival,
                        ExitGuide& here) const;
    void diffuse_guide(const Vec3& x, const Vec3& n, TriangleRef tri, DiffuseGuide& g,
                       std::uint64_t& rays) const;
    void diffuse_guided(const DiffuseGuide& g, const Vec3& x, const Vec3& n, TriangleRef tri,
                        const WalkState<3>& ws, int depth, RngStream& rng, RGB& out,
                        std::uint64_t& rays) const;
    void run_diffuse_guide(CameraPath& c, const Vec3& p, const Vec3& n, TriangleRef tri) const;

    // A camera path and its surface vertices (render.cpp; inline as NEE above).
    inline bool vertex(CameraPath& c, const Vec3& p, Vec3 n, TriangleRef tri) const;
    inline void diffuse_vertex(CameraPath& c, const Vec3& p, Vec3 n, TriangleRef tri,
                               bool left_guided_arrival) const;
    inline bool boundary_vertex(CameraPath& c, const Vec3& p, const Vec3& n, TriangleRef tri,
                                int mi, bool guided_arrival, bool plate_arrival) const;
    inline bool rough_boundary(CameraPath& c, const Vec3& p, const Vec3& n, TriangleRef tri,
                               const MediumData& md, bool outside, bool guided_arrival,
                               bool plate_arrival, ExitGuide& here, bool& here_guided,
                               bool& reflected, bool& transmitted) const;
    struct PathHooks;  // inside a medium: the walk's hooks (render.cpp)
    std::uint64_t trace(int x, int y, int hero, RngStream& rng, double* T) const;
};

}  // namespace ssslab::volpath::render_detail
