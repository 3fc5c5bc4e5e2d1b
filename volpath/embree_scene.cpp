#include "volpath/embree_scene.h"

#include "core/sanitizers.h"

#include <embree3/rtcore.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ssslab::volpath {

struct EmbreeScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<std::vector<Vec3>> normals;  // per shape, per triangle (double precision)
    // Per shape, the vertices of each triangle as Embree stores them (floats, held as doubles):
    // the surface the ray queries see, for the point queries.
    std::vector<std::vector<std::array<Vec3, 4>>> corners;  // and the unit normal of their plane
};

namespace {

std::string device_error(RTCDevice d) {
    switch (rtcGetDeviceError(d)) {
        case RTC_ERROR_NONE:
            return "no error";
        case RTC_ERROR_INVALID_ARGUMENT:
            return "invalid argument";
        case RTC_ERROR_INVALID_OPERATION:
            return "invalid operation";
        case RTC_ERROR_OUT_OF_MEMORY:
            return "out of memory";
        case RTC_ERROR_UNSUPPORTED_CPU:
            return "unsupported CPU";
        case RTC_ERROR_CANCELLED:
            return "cancelled";
        default:
            return "unknown error";
    }
}

// The point of triangle (a, b, c) nearest to p [Ericson, Real-Time Collision Detection, 5.1.5].
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
    const Vec3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

struct PointQuery {
    const std::vector<std::vector<std::array<Vec3, 4>>>* corners;
    Vec3 p;
    double best2;
};

bool point_query(RTCPointQueryFunctionArguments* args) {
    auto* q = static_cast<PointQuery*>(args->userPtr);
    const std::array<Vec3, 4>& t = (*q->corners)[args->geomID][args->primID];
    // No nearer than its plane: most candidates end here.
    const double plane = dot(q->p - t[0], t[3]);
    if (!(plane * plane < q->best2)) return false;
    const Vec3 d = closest_on_triangle(q->p, t[0], t[1], t[2]) - q->p;
    const double d2 = dot(d, d);
    if (!(d2 < q->best2)) return false;
    q->best2 = d2;
    // Shrink the search: a float radius not below the distance.
    args->query->radius =
        std::nextafter(static_cast<float>(std::sqrt(d2)), std::numeric_limits<float>::infinity());
    return true;
}

}  // namespace

EmbreeScene::EmbreeScene(const std::vector<const TriangleMesh*>& meshes) : impl_(new Impl) {
    impl_->device = rtcNewDevice(nullptr);  // builds use all threads; queries the caller's
    if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
    impl_->scene = rtcNewScene(impl_->device);
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
    // The context filter skips the triangle a ray leaves (TriangleRef), only where one is named.
    rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    double extent = 0;
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        const TriangleMesh& m = *meshes[k];
        RTCGeometry g = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                              RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                              m.positions.size()));
        auto* ix = static_cast<unsigned*>(
            rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(unsigned), m.triangles.size()));
        if (!v || !ix) throw std::runtime_error("Embree: " + device_error(impl_->device));
        for (std::size_t i = 0; i < m.positions.size(); ++i) {
            v[3 * i] = static_cast<float>(m.positions[i].x);
            v[3 * i + 1] = static_cast<float>(m.positions[i].y);
            v[3 * i + 2] = static_cast<float>(m.positions[i].z);
            extent = std::max({extent, std::fabs(m.positions[i].x), std::fabs(m.positions[i].y),
                               std::fabs(m.positions[i].z)});
        }
        std::vector<Vec3> normals;
        normals.reserve(m.triangles.size());
        std::vector<std::array<Vec3, 4>> corners;
        corners.reserve(m.triangles.size());
        auto stored = [&](std::uint32_t i) { return Vec3{v[3 * i], v[3 * i + 1], v[3 * i + 2]}; };
        for (std::size_t i = 0; i < m.triangles.size(); ++i) {
            const auto& t = m.triangles[i];
            ix[3 * i] = t[0];
            ix[3 * i + 1] = t[1];
            ix[3 * i + 2] = t[2];
            normals.push_back(m.facet_normal(i));
            const Vec3 a = stored(t[0]), b = stored(t[1]), c = stored(t[2]);
            const Vec3 n = cross(b - a, c - a);
            const double len = length(n);
            // A degenerate triangle has no plane to bound it: a zero normal never rejects.
            corners.push_back({a, b, c, len > 0 ? n * (1 / len) : Vec3{0, 0, 0}});
        }
        impl_->normals.push_back(std::move(normals));
        impl_->corners.push_back(std::move(corners));
        rtcCommitGeometry(g);
        const unsigned id = rtcAttachGeometry(impl_->scene, g);
        rtcReleaseGeometry(g);
        if (id != k) throw std::runtime_error("Embree: unexpected geometry id");
        triangles_ += m.triangles.size();
    }
#ifdef SSSLAB_TSAN
    // The TSan build: Embree's BVH build runs on TBB through task code compiled into the
    // uninstrumented libembree3, so TSan cannot see how a TBB worker that took part in the build
    // is ordered with this thread's later reuse of the build's stack and heap (the reports of
    // tests/tsan.supp, whose pattern catches only stacks that pass through Embree). Built inside
    // an arena of one thread, no worker takes part; our own parallel code is untouched.
    tbb::task_arena one_thread(1);
    one_thread.execute([&] { rtcCommitScene(impl_->scene); });
#else
    rtcCommitScene(impl_->scene);
#endif
    if (rtcGetDeviceError(impl_->device) != RTC_ERROR_NONE)
        throw std::runtime_error("Embree: " + device_error(impl_->device));
    // Single precision: positions carry a relative error of 2^-24; leave a few hundred ulps.
    epsilon_ = std::max(1e-9, 4e-5 * extent);
}

EmbreeScene::~EmbreeScene() {
    if (impl_->scene) rtcReleaseScene(impl_->scene);
    if (impl_->device) rtcReleaseDevice(impl_->device);
}

namespace {

// An intersect context whose filter rejects the hits on one triangle (the one a ray leaves).
struct SkipContext {
    RTCIntersectContext ctx;  // first: Embree hands the filter &ctx
    TriangleRef skip;
};

// Whether candidate i of a filter call is on the triangle the ray leaves.
bool on_skipped(const SkipContext& c, const RTCFilterFunctionNArguments* args, unsigned i) {
    return RTCHitN_geomID(args->hit, args->N, i) == c.skip.shape &&
           RTCHitN_primID(args->hit, args->N, i) == c.skip.triangle;
}

void skip_filter(const RTCFilterFunctionNArguments* args) {
    const auto* c = reinterpret_cast<const SkipContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i)
        if (args->valid[i] == -1 && on_skipped(*c, args, i)) args->valid[i] = 0;
}

// The context of a query, and its near distance: a ray that leaves a triangle skips it and the
// hits within `rounding` past t_min.
float init_context(SkipContext& c, TriangleRef leaving, double t_min, double rounding) {
    rtcInitIntersectContext(&c.ctx);
    if (!leaving.any()) return static_cast<float>(t_min);
    c.ctx.filter = skip_filter;
    c.skip = leaving;
    return static_cast<float>(t_min + rounding);
}

// An Embree ray from o along d over (t_near, t_max] (t_max infinite: unbounded).
RTCRay make_ray(const Vec3& o, const Vec3& d, float t_near, double t_max) {
    RTCRay r{};
    r.org_x = static_cast<float>(o.x);
    r.org_y = static_cast<float>(o.y);
    r.org_z = static_cast<float>(o.z);
    r.dir_x = static_cast<float>(d.x);
    r.dir_y = static_cast<float>(d.y);
    r.dir_z = static_cast<float>(d.z);
    r.tnear = t_near;
    r.tfar =
        std::isfinite(t_max) ? static_cast<float>(t_max) : std::numeric_limits<float>::infinity();
    r.mask = 0xffffffffu;
    r.flags = 0;
    return r;
}

// The context of crossings(): the triangle skipped, the passable shapes and the hits on them.
struct CrossContext {
    SkipContext base;  // first: Embree hands the filter &base.ctx
    const std::vector<char>* passable;
    EmbreeScene::Crossing* out;
    std::size_t cap, n;
    bool overflow;
};

// Accepts (and so ends the occlusion query with) a hit on an opaque shape, or the first hit
// that finds the buffer full; records and rejects the hits on passable shapes. Embree writes
// the candidate's distance into the ray's tfar before it calls the filter.
void cross_filter(const RTCFilterFunctionNArguments* args) {
    auto* c = reinterpret_cast<CrossContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        if (on_skipped(c->base, args, i)) {
            args->valid[i] = 0;
            continue;
        }
        const unsigned geom = RTCHitN_geomID(args->hit, args->N, i);
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        if (!(*c->passable)[geom]) continue;
        if (c->n == c->cap) {
            c->overflow = true;
            continue;
        }
        c->out[c->n++] = {RTCRayN_tfar(args->ray, args->N, i), geom, prim};
        args->valid[i] = 0;
    }
}

}  // namespace

const Vec3& EmbreeScene::normal(std::uint32_t shape, std::uint32_t triangle) const {
    return impl_->normals[shape][triangle];
}

EmbreeScene::Through EmbreeScene::crossings(const Vec3& o, const Vec3& d, double t_min,
                                            double t_max, TriangleRef leaving,
                                            const std::vector<char>& passable, Crossing* out,
                                            std::size_t cap, std::size_t& n) const {
    CrossContext ctx{{}, &passable, out, cap, 0, false};
    const float t_near = init_context(ctx.base, leaving, t_min, rounding());
    ctx.base.ctx.filter = cross_filter;  // also where no triangle is skipped
    RTCRay r = make_ray(o, d, t_near, t_max);
    rtcOccluded1(impl_->scene, &ctx.base.ctx, &r);
    n = ctx.n;
    if (ctx.overflow) return Through::kTooMany;
    return r.tfar < 0 ? Through::kBlocked : Through::kClear;
}

RayHit EmbreeScene::intersect(const Vec3& o, const Vec3& d, double t_min, double t_max,
                              TriangleRef leaving) const {
    SkipContext ctx;
    const float t_near = init_context(ctx, leaving, t_min, rounding());
    RTCRayHit rh{};
    rh.ray = make_ray(o, d, t_near, t_max);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &ctx.ctx, &rh);
    RayHit out;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return out;
    out.t = rh.ray.tfar;
    out.shape = rh.hit.geomID;
    out.triangle = rh.hit.primID;
    out.normal = impl_->normals[out.shape][out.triangle];
    return out;
}

double EmbreeScene::distance_to_surface(const Vec3& p, double max_distance) const {
    RTCPointQuery query;
    query.x = static_cast<float>(p.x);
    query.y = static_cast<float>(p.y);
    query.z = static_cast<float>(p.z);
    query.time = 0;
    query.radius = std::isfinite(max_distance) ? static_cast<float>(max_distance)
                                               : std::numeric_limits<float>::infinity();
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    PointQuery q{&impl_->corners, p, max_distance * max_distance};
    rtcPointQuery(impl_->scene, &query, &ctx, point_query, &q);
    return std::min(max_distance, std::sqrt(q.best2));
}

bool EmbreeScene::occluded(const Vec3& o, const Vec3& d, double t_min, double t_max,
                           TriangleRef leaving) const {
    SkipContext ctx;
    const float t_near = init_context(ctx, leaving, t_min, rounding());
    RTCRay r = make_ray(o, d, t_near, t_max);
    rtcOccluded1(impl_->scene, &ctx.ctx, &r);
    return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}

}  // namespace ssslab::volpath
