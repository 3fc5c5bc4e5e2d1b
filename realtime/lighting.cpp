// Pass 1 of the real-time renderer (see lighting.h). Sources:
//   [Walter et al. 2007] "Microfacet models for refraction through rough surfaces", EGSR: the
//     rough dielectric (core/dielectric.h), its Jacobian d(w_m)/d(w_i) (Eqs. 14 and 17).
//   [Williams 1978] "Casting curved shadows on curved surfaces": shadow maps.
//   [Jimenez et al. 2010] "Real-time realistic skin translucency", IEEE CG&A: thickness from
//     the shadow map, transmittance of the thin part seen from behind.
//   [Swinbank and Purser 2006] Fibonacci grids: the stratified directions and points.
#include "realtime/lighting.h"

#include "core/cpu_dispatch.h"
#include "core/dielectric.h"
#include "realtime/shadow_map.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace ssslab::realtime {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
using RGB = std::array<double, 3>;

enum class Kind : std::uint8_t { kNone, kDiffuse, kMedium };

struct Receiver {
    Vec3 p, n;  // position, outward facet normal
    Vec3 ns;    // shading normal: diffuse towards the camera, medium the outward one
    Vec3 wo;    // towards the camera: unit for media; diffuse receivers use only its side
    Kind kind = Kind::kNone;
    int shape = -1, material = -1;
};

// What a light sample gives a receiver at p: the direction towards the light and the irradiance
// at normal incidence (false where its lobe faces away or p is at the light).
bool incident_light(const LightSample& s, const Vec3& p, Vec3& wi, RGB& E) {
    if (s.directional) {
        wi = s.w;
        E = s.value;
        return true;
    }
    const Vec3 d = s.pos - p;
    const double d2 = dot(d, d);
    if (!(d2 > 0)) return false;
    wi = d * (1 / std::sqrt(d2));
    double k = 1 / d2;
    if (s.lobe) k *= s.factor(wi);
    if (!(k > 0)) return false;
    for (std::size_t c = 0; c < 3; ++c) E[c] = s.value[c] * k;
    return true;
}

// Sphere lights are not in the shadow maps (as they are not in volpath's BVH), but they occlude
// what lies behind them: whether one of `spheres` (indices into scene.lights) other than the
// sample's own lies between p and the sample along wi.
bool behind_sphere(const std::vector<Light>& lights, const std::vector<int>& spheres,
                   const LightSample& s, const Vec3& p, const Vec3& wi) {
    const double dist = s.directional ? kInf : length(s.pos - p);
    for (int k : spheres) {
        if (k == s.light) continue;
        if (lights[static_cast<std::size_t>(k)].hit(p, wi) < dist) return true;
    }
    return false;
}

std::vector<int> sphere_lights(const std::vector<Light>& lights) {
    std::vector<int> spheres;
    for (std::size_t k = 0; k < lights.size(); ++k)
        if (lights[k].has_surface()) spheres.push_back(static_cast<int>(k));
    return spheres;
}

// Boundaries: one transmittance per (eta, alpha) of the scene's media, tabulated once per process
// (as an engine precomputes its lookup tables at load time, not every frame); nullptr for
// diffuse materials.
std::vector<const BoundaryTransmittance*> boundary_tables(const Scene& scene,
                                                          const LightingOptions& o) {
    std::vector<const BoundaryTransmittance*> mat_T(scene.materials.size(), nullptr);
    for (std::size_t m = 0; m < scene.materials.size(); ++m) {
        const SceneMaterial& sm = scene.materials[m];
        if (sm.kind != SceneMaterial::Kind::kMedium) continue;
        const auto [eta, alpha] = sm.boundary();
        mat_T[m] =
            &tabulated_boundary(eta, alpha, o.transmittance_cosines, o.transmittance_quadrature);
    }
    return mat_T;
}

// The first of a light sample's views that p projects into (an orthographic view takes every
// point); views.size() if none.
std::size_t first_view(const std::vector<ShadowView>& views, const Vec3& p) {
    for (std::size_t k = 0; k < views.size(); ++k) {
        const ClipVertex c = views[k].to_clip(p);
        if (views[k].orthographic || (c.w > 0 && std::abs(c.x) <= c.w && std::abs(c.y) <= c.w))
            return k;
    }
    return views.size();
}

// The shadow test of a receiver with facet normal n, lit from wi, whose map coordinates are pc:
// looked up at p + nl * normal_offset (nl = n on the light's side; by linearity of the
// projection), lit where that lies outside the map or within the bias of the texel's first
// surface. The texel's size at the point's depth (pc.w).
bool lit_in_map(const ShadowMap& sm, const ShadowView& view, const ShadowView::Projection& proj,
                const ClipVertex& pc, const Vec3& n, const Vec3& wi, const LightingOptions& o) {
    const double texel = view.texel_size(view.orthographic ? 0.0 : pc.w);
    const Vec3 nl = dot(n, wi) >= 0 ? n : -n;
    const double off = o.normal_offset_texels * texel;
    const ClipVertex dn = proj.along(nl);
    const ClipVertex qc{pc.x + dn.x * off, pc.y + dn.y * off, pc.w + dn.w * off};
    std::size_t ti = 0;
    return !sm.texel_of(qc, ti) || qc.w <= sm.depth[ti] + o.depth_bias_texels * texel;
}

// A directional light sample's shadow test, one orthographic map, per sample of a row: what
// shade()'s light pass computes per receiver up to the lit/unlit decision, the same
// expressions in the same order (so the same bits), over plain arrays in one branch-free loop
// that the compiler vectorises (AVX2 where the machine has it, chosen at run time; the results
// do not depend on it).
struct DirectionalRow {
    Vec3 camera, forward, right, up;  // RasterCamera::SampleRays
    Vec3 w;                           // towards the light (unit)
    ShadowView::Projection proj;
    double offset = 0;  // normal offset: normal_offset_texels * texel
    double bias = 0;    // depth_bias_texels * texel
    int size = 0;       // texels per side
};

typedef double D4 __attribute__((vector_size(32)));
typedef std::int64_t M4 __attribute__((vector_size(32)));  // lane masks: -1 true, 0 false
typedef std::int32_t I4 __attribute__((vector_size(16)));

// Four samples at a time in GCC's vector extensions (one AVX register, or two SSE2 ones); a
// row's last samples as a padded quad.
SSSLAB_AVX2_CLONES void directional_row(const DirectionalRow& k, int n, const double* ndc_x,
                                        double ndc_y, const double* view_z, const float* normal,
                                        const Kind* kind, const float* depth, double* cos_out,
                                        std::uint8_t* lit_out) {
    const double size = k.size;
    const D4 zero4{}, one4 = zero4 + 1.0, size4 = zero4 + size;
    for (int x = 0; x < n; x += 4) {
        // The last, partial quad reads padded copies (nothing seen there) and writes back only
        // its samples: one body for every sample.
        const int m = std::min(4, n - x);
        double pad_ndc[4] = {0, 0, 0, 0}, pad_z[4] = {1, 1, 1, 1}, pad_cos[4];
        float pad_n[12] = {};
        Kind pad_kind[4] = {Kind::kNone, Kind::kNone, Kind::kNone, Kind::kNone};
        std::uint8_t pad_lit[4];
        const double* in_ndc = ndc_x + x;
        const double* in_z = view_z + x;
        const float* in_n = normal + 3 * x;
        const Kind* in_kind = kind + x;
        double* out_cos = cos_out + x;
        std::uint8_t* out_lit = lit_out + x;
        if (m < 4) {
            std::copy_n(in_ndc, m, pad_ndc);
            std::copy_n(in_z, m, pad_z);
            std::copy_n(in_n, 3 * m, pad_n);
            std::copy_n(in_kind, m, pad_kind);
            in_ndc = pad_ndc, in_z = pad_z, in_n = pad_n, in_kind = pad_kind;
            out_cos = pad_cos, out_lit = pad_lit;
        }
        D4 nx_, z, nx, ny, nz;
        M4 medium, diffuse;
        std::memcpy(&nx_, in_ndc, sizeof nx_);
        std::memcpy(&z, in_z, sizeof z);
        for (int j = 0; j < 4; ++j) {
            nx[j] = in_n[3 * j];
            ny[j] = in_n[3 * j + 1];
            nz[j] = in_n[3 * j + 2];
            medium[j] = in_kind[j] == Kind::kMedium ? -1 : 0;
            diffuse[j] = in_kind[j] == Kind::kDiffuse ? -1 : 0;
        }
        // receiver_at: the point on the camera ray, the normal, the direction to the camera.
        const D4 dx = k.forward.x + k.right.x * nx_ + k.up.x * ndc_y;
        const D4 dy = k.forward.y + k.right.y * nx_ + k.up.y * ndc_y;
        const D4 dz = k.forward.z + k.right.z * nx_ + k.up.z * ndc_y;
        const D4 px = k.camera.x + dx * z, py = k.camera.y + dy * z, pz = k.camera.z + dz * z;
        const D4 len2 = dx * dx + dy * dy + dz * dz;
        D4 len;
        for (int j = 0; j < 4; ++j) len[j] = std::sqrt(len2[j]);
        const D4 inv = 1.0 / len;
        const D4 ox = medium ? -(dx * inv) : -dx, oy = medium ? -(dy * inv) : -dy,
                 oz = medium ? -(dz * inv) : -dz;
        const M4 flip = diffuse & (nx * ox + ny * oy + nz * oz < 0);
        const D4 sx = flip ? -nx : nx, sy = flip ? -ny : ny, sz = flip ? -nz : nz;
        const D4 cs = sx * k.w.x + sy * k.w.y + sz * k.w.z;
        std::memcpy(out_cos, &cs, sizeof cs);
        // The map coordinates of the normal-offset point, the nearest texel, the depth test.
        const D4 ax = px - k.proj.origin.x, ay = py - k.proj.origin.y, az = pz - k.proj.origin.z;
        const D4 cx = ax * k.proj.x.x + ay * k.proj.x.y + az * k.proj.x.z;
        const D4 cy = ax * k.proj.y.x + ay * k.proj.y.y + az * k.proj.y.z;
        const D4 cw = ax * k.proj.w.x + ay * k.proj.w.y + az * k.proj.w.z;
        const M4 front = nx * k.w.x + ny * k.w.y + nz * k.w.z >= 0;
        const D4 lx = front ? nx : -nx, ly = front ? ny : -ny, lz = front ? nz : -nz;
        const D4 qx = cx + (lx * k.proj.x.x + ly * k.proj.x.y + lz * k.proj.x.z) * k.offset;
        const D4 qy = cy + (lx * k.proj.y.x + ly * k.proj.y.y + lz * k.proj.y.z) * k.offset;
        const D4 qw = cw + (lx * k.proj.w.x + ly * k.proj.w.y + lz * k.proj.w.z) * k.offset;
        const D4 fx = (qx + 1) * 0.5 * size4, fy = (one4 - qy) * 0.5 * size4;
        const M4 inside = (fx >= 0) & (fy >= 0) & (fx < size4) & (fy < size4);
        const I4 tx = __builtin_convertvector(inside ? fx : zero4, I4);
        const I4 ty = __builtin_convertvector(inside ? fy : zero4, I4);
        const I4 ti = ty * k.size + tx;
        D4 map_depth;
        for (int j = 0; j < 4; ++j) map_depth[j] = depth[ti[j]];
        const M4 lit = ~inside | (qw <= map_depth + k.bias);
        for (int j = 0; j < 4; ++j) out_lit[j] = lit[j] != 0;
        if (m < 4) {
            std::copy_n(pad_cos, m, cos_out + x);
            std::copy_n(pad_lit, m, lit_out + x);
        }
    }
}

}  // namespace

void GBuffer::resize(int w, int h) {
    width = w;
    height = h;
    const std::size_t n = samples();
    view_z.resize(n);
    ray_t.resize(n);
    normal.resize(3 * n);
    shape.resize(n);
    material.resize(n);
    irradiance.resize(3 * n);
    exit_weight.resize(n);
    specular.resize(3 * n);
    surface.resize(3 * n);
    thickness.resize(n);
    translucency.resize(3 * n);
}

bool any_slab_table(const std::vector<SlabTransmittance>& slabs) {
    return std::any_of(slabs.begin(), slabs.end(),
                       [](const SlabTransmittance& t) { return !t.thickness_mm.empty(); });
}

std::array<double, 3> SlabTransmittance::at(double d) const {
    std::array<double, 3> r{};
    const std::size_t n = std::min(thickness_mm.size(), transmittance.size());
    if (n == 0) return r;
    if (!(d > thickness_mm[0])) return transmittance[0];
    if (d >= thickness_mm[n - 1]) return transmittance[n - 1];
    const std::size_t k = static_cast<std::size_t>(
        std::upper_bound(thickness_mm.begin(), thickness_mm.begin() + static_cast<long>(n), d) -
        thickness_mm.begin());
    const double d0 = thickness_mm[k - 1], d1 = thickness_mm[k];
    const double t = (d - d0) / (d1 - d0);
    for (std::size_t c = 0; c < 3; ++c) {
        const double a = transmittance[k - 1][c], b = transmittance[k][c];
        r[c] = a > 0 && b > 0 ? std::exp(std::log(a) + t * (std::log(b) - std::log(a)))
                              : a + t * (b - a);
    }
    return r;
}

double BoundaryTransmittance::ggx(double mu, double eta, double alpha, int q) {
    using namespace dielectric;
    if (!(mu > 0)) return 0;
    mu = std::min(mu, 1.0);
    const Vec3 wo{std::sqrt(std::max(0.0, 1 - mu * mu)), 0, mu};
    // Microfacet normals m in the coordinates of the GGX distribution D(m) cos(theta_m) dw_m =
    // du dphi / (2 pi): tan^2 theta_m = alpha^2 u / (1 - u). The integrand grows as
    // 1 / cos(theta_m) ~ 1 / sqrt(1 - u) towards grazing microfacets, so u = 1 - v^2 (du = 2 v
    // dv) makes it smooth; midpoint rule in v and in phi over [0, pi] (the lobe is symmetric
    // about the plane of incidence). Then
    // T = integral f(wo, wi) |cos theta_i| dw_i = integral f |cos theta_i| / |dw_m/dw_i| dw_m,
    // with wi the refraction of wo through m.
    double sum = 0;
    for (int a = 0; a < q; ++a) {
        const double v = (a + 0.5) / q, u = 1 - v * v, jac = 2 * v;
        const double t2 = alpha * alpha * u / (v * v);
        const double ct = 1 / std::sqrt(1 + t2), st = std::sqrt(t2) * ct;
        for (int b = 0; b < q; ++b) {
            const double phi = kPi * (b + 0.5) / q;
            const Vec3 m{st * std::cos(phi), st * std::sin(phi), ct};
            const double h = dot(wo, m);
            if (!(h > 0)) continue;
            double cos_t = 0;
            const double F = fresnel_dielectric(h, eta, cos_t);
            if (F >= 1) continue;
            const Vec3 wi = normalize(-wo * (1 / eta) + m * (h / eta - cos_t));
            if (!(wi.z < 0)) continue;
            const double f = rough_dielectric_f(wo, wi, eta, alpha, TransportMode::kImportance);
            const double dd = dot(wi, m) + h / eta;
            const double dwm_dwi = std::abs(dot(wi, m)) / (dd * dd);
            const double dens = ggx::D(m, alpha) * ct;  // per unit solid angle of m, du dphi/2pi
            if (!(dens > 0) || !(dwm_dwi > 0)) continue;
            sum += jac * f * std::abs(wi.z) / (dwm_dwi * dens);
        }
    }
    // integral over (v, phi in [0, 2 pi)) of g 2 v dv dphi / (2 pi), phi folded: 2 pi / q / (2 pi).
    return sum / (static_cast<double>(q) * q);
}

BoundaryTransmittance::BoundaryTransmittance(double eta, double alpha, int cosines, int q)
    : eta_(eta), alpha_(eta == 1.0 ? 0.0 : alpha) {
    if (!(eta > 0) || !(alpha >= 0) || cosines < 2 || q < 1)
        throw std::invalid_argument("BoundaryTransmittance: eta, alpha or table size out of range");
    if (alpha_ == 0) {
        // c = 2 integral (1 - F) mu dmu, Gauss-Legendre would do; a fine midpoint rule keeps it
        // simple and to ~1e-9 (the integrand's only kink is the critical angle when eta < 1).
        const int n = 1 << 16;
        double s = 0;
        for (int k = 0; k < n; ++k) {
            const double mu = (k + 0.5) / n;
            s += (1 - dielectric::fresnel_dielectric(mu, eta)) * mu;
        }
        c_ = 2 * s / n;
        return;
    }
    table_.resize(static_cast<std::size_t>(cosines));
    tbb::parallel_for(0, cosines, [&](int k) {
        table_[static_cast<std::size_t>(k)] =
            ggx(static_cast<double>(k) / (cosines - 1), eta, alpha_, q);
    });
    // Exactly for the piecewise-linear T: 2 sum over segments of integral T(mu) mu dmu.
    const double h = 1.0 / (cosines - 1);
    double s = 0;
    for (int k = 0; k + 1 < cosines; ++k) {
        const double m0 = k * h, T0 = table_[static_cast<std::size_t>(k)];
        const double dT = table_[static_cast<std::size_t>(k) + 1] - T0;
        s += h * (T0 * m0 + T0 * h / 2 + dT * m0 / 2 + dT * h / 3);
    }
    c_ = 2 * s;
}

double BoundaryTransmittance::operator()(double mu) const {
    if (!(mu > 0)) return 0;
    mu = std::min(mu, 1.0);
    if (alpha_ == 0) return 1 - dielectric::fresnel_dielectric(mu, eta_);
    const double x = mu * static_cast<double>(table_.size() - 1);
    const std::size_t k = std::min(static_cast<std::size_t>(x), table_.size() - 2);
    const double t = x - static_cast<double>(k);
    return table_[k] + t * (table_[k + 1] - table_[k]);
}

double BoundaryTransmittance::exit_weight(double mu_o) const {
    return c_ > 0 ? (*this)(mu_o) / (kPi * c_) : 0.0;
}

const BoundaryTransmittance& tabulated_boundary(double eta, double alpha, int cosines, int q) {
    // Never evicted: a handful of tables of 65 doubles. The lock is held while a new table is
    // built, so that two threads asking for the same one build it once.
    static std::mutex mutex;
    static std::map<std::tuple<double, double, int, int>, BoundaryTransmittance> tables;
    const std::lock_guard<std::mutex> lock(mutex);
    const auto key = std::make_tuple(eta, alpha, cosines, q);
    auto it = tables.find(key);
    if (it == tables.end())
        it = tables.emplace(key, BoundaryTransmittance(eta, alpha, cosines, q)).first;
    return it->second;
}

LightPlan plan_lights(const Scene& scene, const Box& receivers, const LightingOptions& o) {
    return plan_lights(scene, receivers, o,
                       std::vector<Light>(scene.lights.begin(), scene.lights.end()));
}

LightPlan plan_lights(const Scene& scene, const Box& receivers, const LightingOptions& o,
                      std::vector<Light> resolved) {
    if (resolved.size() != scene.lights.size())
        throw std::invalid_argument("plan_lights: the lights are not the scene's");
    LightPlan plan;
    plan.receivers = receivers;
    plan.lights = std::move(resolved);
    Box& casters = plan.casters;
    for (const SceneShape& s : scene.shapes) {
        const auto b = s.mesh.bounds();
        if (b[0].x <= b[1].x) {
            casters.add(b[0]);
            casters.add(b[1]);
        }
    }
    const double scene_size =
        casters.empty() ? 1.0 : std::max(1e-300, length(casters.hi - casters.lo));
    plan.near = 1e-6 * scene_size;

    // Light samples, in scene order: each light's stratified emitters (core/light.h), and the
    // first light's single view for the thickness layer (the emitter itself for a delta light).
    std::vector<LightSample>& samples = plan.samples;
    bool thickness_taken = false;
    for (std::size_t li = 0; li < plan.lights.size(); ++li) {
        const Light& l = plan.lights[li];
        LightEmitter centre;
        const bool has_centre = l.centre(centre);
        const bool first = o.thickness_layer && !thickness_taken && has_centre;
        thickness_taken = thickness_taken || first;
        const std::vector<LightEmitter> emitters =
            l.stratify(o.light_samples, o.environment_samples, receivers.lo, receivers.hi);
        auto push = [&](const LightEmitter& e, bool thickness, bool lights) {
            LightSample s;
            static_cast<LightEmitter&>(s) = e;
            s.thickness_view = thickness;
            s.lights = lights;
            s.light = static_cast<int>(li);
            samples.push_back(s);
        };
        const bool single = l.is_delta();
        for (const LightEmitter& e : emitters) push(e, first && single, true);
        if (first && !single && !emitters.empty()) push(centre, true, false);
    }
    return plan;
}

std::vector<ShadowView> LightPlan::views(const LightSample& s, const LightingOptions& o) const {
    if (s.directional)
        return {fit_directional(s.w, receivers, casters,
                                s.environment ? o.environment_map_size : o.shadow_map_size)};
    return fit_point(s.pos, receivers, near, o.shadow_map_size);
}

void check_lighting_options(const LightingOptions& o) {
    if (o.light_samples < 1 || o.environment_samples < 1 || o.shadow_map_size < 1 ||
        o.shadow_map_size > 16384 || o.environment_map_size < 1 || o.environment_map_size > 16384 ||
        o.transmittance_cosines < 2 || o.transmittance_quadrature < 1)
        throw std::invalid_argument("lighting: options out of range");
}

void check_lighting_inputs(const RasterCamera& camera, const RasterFrame& frame,
                           const LightingOptions& o) {
    const int ss = frame.supersample;
    const std::size_t N = static_cast<std::size_t>(frame.sample_width()) *
                          static_cast<std::size_t>(frame.sample_height());
    if (camera.width != frame.width || camera.height != frame.height || ss < 1 ||
        frame.view_z.size() != N || frame.shape.size() != N || frame.triangle.size() != N ||
        frame.ray_t.size() != N)
        throw std::invalid_argument("lighting: the frame does not match the camera");
    check_lighting_options(o);
}

GBuffer shade(const Scene& scene, const RasterCamera& camera, const RasterFrame& frame,
              const LightingOptions& o, const std::vector<SlabTransmittance>& slabs,
              LightingStats* stats) {
    GBuffer g;
    shade(scene, camera, frame, o, slabs, stats, g);
    return g;
}

namespace {

// The corners of the receivers' box that shade()'s receiver pass grows over a range of rows, as
// plain numbers (Box::add per sample is a call).
struct RowBox {
    double lo[3], hi[3];
    explicit RowBox(const Box& box)
        : lo{box.lo.x, box.lo.y, box.lo.z}, hi{box.hi.x, box.hi.y, box.hi.z} {}
    void grow(const Vec3& p) {
        for (int c = 0; c < 3; ++c) {
            lo[c] = std::min(lo[c], p[c]);
            hi[c] = std::max(hi[c], p[c]);
        }
    }
    // Writes the corners back into `box`.
    void store(Box& box) const {
        box.lo = {lo[0], lo[1], lo[2]};
        box.hi = {hi[0], hi[1], hi[2]};
    }
};

// Scratch of the calling thread, kept between frames (shade() takes references: the passes'
// worker threads must see this thread's, not theirs).
struct ShadeScratch {
    std::vector<Kind> kind;                // the receivers' kinds
    std::vector<std::vector<Vec3>> facet;  // facet normals per shape
    ShadowMap map;                         // the shadow map of the view being lit
    std::vector<std::uint8_t> face;        // the cube face of each receiver
};
ShadeScratch& shade_scratch() {
    static thread_local ShadeScratch scratch;
    return scratch;
}

constexpr std::uint8_t kNoFace = 255;  // a receiver in none of a light sample's views

// One shade() call: its inputs, the G-buffer it writes, the tables per material and per shape,
// and the receivers' kinds; the receiver pass, then the light samples one at a time.
struct ShadePass {
    const Scene& scene;
    const RasterCamera& camera;
    const RasterFrame& frame;
    const LightingOptions& o;
    const std::vector<SlabTransmittance>& slabs;
    GBuffer& g;
    const int W, H;
    const std::size_t N;
    const std::vector<const BoundaryTransmittance*> mat_T;
    std::vector<RGB> albedo_pi;  // Lambert's albedo / pi per diffuse material
    // Receivers and what the camera sees directly. A receiver (position, normals, direction
    // to the camera) is not stored: each pass over the light samples recomputes it from the
    // G-buffer (a few flops against ~100 bytes a sample of memory traffic), and only its kind
    // is kept.
    std::vector<Kind>& kind;
    // The camera rays of RasterCamera::ray_direction, to the bit.
    const RasterCamera::SampleRays rays;
    // Facet normals as volpath/embree_scene.cpp computes them (double precision), once per
    // triangle rather than once per sample and light.
    std::vector<std::vector<Vec3>>& facet;
    // Per shape: its material and whether that is a medium.
    std::vector<int> shape_material;
    std::vector<char> shape_medium;
    // The light pass's: the plan, its sphere lights, whether any material has a slab table, the
    // shadow map (one map at a time, its storage reused from map to map and from frame to
    // frame; the result does not depend on it), the receivers' cube faces (light samples with
    // several views), the maps rendered and their time.
    const LightPlan* plan = nullptr;
    std::vector<int> spheres;
    bool any_slab = false;
    ShadowMap& sm;
    std::vector<std::uint8_t>& face;
    double shadow_ms = 0;
    int maps = 0;

    ShadePass(const Scene& scene_, const RasterCamera& camera_, const RasterFrame& frame_,
              const LightingOptions& o_, const std::vector<SlabTransmittance>& slabs_, GBuffer& out)
        : scene(scene_),
          camera(camera_),
          frame(frame_),
          o(o_),
          slabs(slabs_),
          g(out),
          W(frame_.sample_width()),
          H(frame_.sample_height()),
          N(static_cast<std::size_t>(W) * static_cast<std::size_t>(H)),
          mat_T(boundary_tables(scene_, o_)),
          albedo_pi(scene_.materials.size()),
          kind(shade_scratch().kind),
          rays(camera_.sample_rays(frame_.supersample)),
          facet(shade_scratch().facet),
          shape_material(scene_.shapes.size()),
          shape_medium(scene_.shapes.size()),
          sm(shade_scratch().map),
          face(shade_scratch().face) {
        // Sized only: the first pass below writes every entry of every array (a reused
        // G-buffer of the same size keeps its storage and is not cleared twice).
        g.resize(W, H);
        for (std::size_t m = 0; m < scene.materials.size(); ++m)
            for (std::size_t c = 0; c < 3; ++c)
                albedo_pi[m][c] = scene.materials[m].albedo[c] / kPi;
        kind.resize(N);  // written for every sample by the first pass below
        facet.resize(scene.shapes.size());
        for (std::size_t k = 0; k < scene.shapes.size(); ++k) {
            const TriangleMesh& m = scene.shapes[k].mesh;
            facet[k].resize(m.triangles.size());
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.triangles.size(), 4096),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  for (std::size_t t = r.begin(); t != r.end(); ++t)
                                      facet[k][t] = m.facet_normal(t);
                              });
        }
        for (std::size_t k = 0; k < scene.shapes.size(); ++k) {
            shape_material[k] = scene.shapes[k].material;
            shape_medium[k] = scene.materials[static_cast<std::size_t>(shape_material[k])].kind ==
                              SceneMaterial::Kind::kMedium;
        }
    }

    // Material m's slab table; nullptr where it has none.
    const SlabTransmittance* slab_of(int m) const {
        if (m < 0 || static_cast<std::size_t>(m) >= slabs.size()) return nullptr;
        const SlabTransmittance& s = slabs[static_cast<std::size_t>(m)];
        return s.empty() ? nullptr : &s;
    }

    // The receiver of sample (sx, sy), i its index, from the G-buffer as the first pass below
    // wrote it: the point at the sample's view depth on its camera ray (the rasterizer's depth
    // is that of the ray-plane intersection, to rounding), the facet normal as the G-buffer
    // holds it (float), and the camera ray normalized only where its length matters (a
    // medium's boundary terms). Every pass sees the same receiver.
    Vec3 point_at(std::size_t i, const Vec3& du) const {
        return camera.position + du * frame.view_z[i];
    }
    Receiver receiver_at(std::size_t i, int sx, int sy) const {
        Receiver r;
        const Vec3 du = rays.unnormalized(sx, sy);
        r.p = point_at(i, du);
        r.n = {g.normal[3 * i], g.normal[3 * i + 1], g.normal[3 * i + 2]};
        r.kind = kind[i];
        r.wo = r.kind == Kind::kMedium ? -normalize(du) : -du;
        r.shape = g.shape[i];
        r.material = g.material[i];
        r.ns = r.kind == Kind::kDiffuse && dot(r.n, r.wo) < 0 ? -r.n : r.n;
        return r;
    }

    // ---- The receiver pass.

    // Every entry of the row starting at sample `row` that is not written per sample: the
    // lighting layers start at 0, depths and shapes as they are (the raster frame holds +inf, 0
    // and -1 where nothing is seen, what the G-buffer holds there), in loops that vectorise.
    void start_row(std::size_t row) {
        const auto w = static_cast<std::size_t>(W);
        std::fill_n(g.irradiance.begin() + static_cast<std::ptrdiff_t>(3 * row), 3 * w, 0.f);
        std::fill_n(g.specular.begin() + static_cast<std::ptrdiff_t>(3 * row), 3 * w, 0.f);
        std::fill_n(g.translucency.begin() + static_cast<std::ptrdiff_t>(3 * row), 3 * w, 0.f);
        std::fill_n(g.surface.begin() + static_cast<std::ptrdiff_t>(3 * row), 3 * w, 0.f);
        std::fill_n(g.exit_weight.begin() + static_cast<std::ptrdiff_t>(row), w, 0.f);
        std::fill_n(g.thickness.begin() + static_cast<std::ptrdiff_t>(row), w, 0.f);
        const double* vz = &frame.view_z[row];
        const double* rt = &frame.ray_t[row];
        float* gz = &g.view_z[row];
        float* gt = &g.ray_t[row];
        for (std::size_t x = 0; x < w; ++x) gz[x] = static_cast<float>(vz[x]);
        for (std::size_t x = 0; x < w; ++x) gt[x] = static_cast<float>(rt[x]);
        std::copy_n(&frame.shape[row], w, &g.shape[row]);
    }

    // Sample i = (sx, sy): its material, normal and kind of receiver, what it shows where no
    // light pass lights it (a sphere light in front, the sky), and for a medium seen from
    // outside its exit weight and a smooth boundary's mirror reflection; `box` grows by the
    // receivers. The nearest sphere light along a ray and what a ray that meets no geometry
    // sees (the environment and the suns' discs) from `lights`.
    void receive_sample(std::size_t i, int sx, int sy, const std::vector<Light>& lights,
                        bool any_sphere, RowBox& box) {
        const int s = frame.shape[i];
        kind[i] = Kind::kNone;
        // Sphere lights are not rasterized (nor in volpath's BVH): the nearest in front of the
        // geometry is what the sample shows.
        const Light* light_in_front = nullptr;
        if (any_sphere || s < 0) {
            const Vec3 d = rays.direction(sx, sy);
            double tl = kInf;
            const Light* hit = nearest_light_surface(lights, camera.position, d, tl);
            if (hit && (s < 0 || tl < frame.ray_t[i])) light_in_front = hit;
            if (s < 0) {
                const RGB surf = hit ? hit->L : escaped_radiance(lights, d);
                for (std::size_t c = 0; c < 3; ++c)
                    g.surface[3 * i + c] = static_cast<float>(surf[c]);
            }
        }
        if (s < 0) {
            g.material[i] = -1;
            for (std::size_t c = 0; c < 3; ++c) g.normal[3 * i + c] = 0.f;
            return;
        }
        const auto su = static_cast<std::size_t>(s);
        const int mat = shape_material[su];
        const bool medium = shape_medium[su] != 0;
        g.material[i] = mat;
        const Vec3& fn = facet[su][frame.triangle[i]];
        for (int c = 0; c < 3; ++c)
            g.normal[3 * i + static_cast<std::size_t>(c)] = static_cast<float>(fn[c]);
        if (light_in_front) {  // a sphere light in front: nothing to light
            for (std::size_t c = 0; c < 3; ++c)
                g.surface[3 * i + c] = static_cast<float>(light_in_front->L[c]);
            return;
        }
        if (!medium) {
            kind[i] = Kind::kDiffuse;
            box.grow(point_at(i, rays.unnormalized(sx, sy)));  // all the box needs
            return;
        }
        // A medium is provisional until it is seen from outside (below).
        kind[i] = Kind::kMedium;
        const Receiver r = receiver_at(i, sx, sy);
        if (!(dot(r.n, r.wo) > 0)) {
            kind[i] = Kind::kNone;  // a medium seen from inside: not lit here
            return;
        }
        box.grow(r.p);
        const BoundaryTransmittance& T = *mat_T[static_cast<std::size_t>(mat)];
        g.exit_weight[i] = static_cast<float>(T.exit_weight(dot(r.n, r.wo)));
        if (T.alpha() == 0) {
            // Mirror: F times what the reflected ray sees of the sphere lights, the
            // environment and the suns (unoccluded).
            const Vec3 rd = r.n * (2 * dot(r.n, r.wo)) - r.wo;
            const double F = dielectric::fresnel_dielectric(dot(r.n, r.wo), T.eta());
            double tb = kInf;
            const Light* sl = nearest_light_surface(lights, r.p, rd, tb);
            const RGB Lr = sl ? sl->L : escaped_radiance(lights, rd);
            for (std::size_t c = 0; c < 3; ++c)
                g.specular[3 * i + c] = static_cast<float>(F * Lr[c]);
        }
    }

    // The first pass: every entry of the G-buffer written (receive_sample per sample), the
    // receivers' kinds; returns the receivers' box that the shadow maps are fitted to.
    Box receiver_pass(const std::vector<Light>& lights) {
        const bool any_sphere = !sphere_lights(lights).empty();
        return tbb::parallel_reduce(
            tbb::blocked_range<int>(0, H), Box{},
            [&](const tbb::blocked_range<int>& rows, Box box) {
                RowBox grown(box);
                for (int sy = rows.begin(); sy != rows.end(); ++sy) {
                    const std::size_t row = frame.sample_index(0, sy);
                    start_row(row);
                    for (int sx = 0; sx < W; ++sx)
                        receive_sample(row + static_cast<std::size_t>(sx), sx, sy, lights,
                                       any_sphere, grown);
                }
                grown.store(box);
                return box;
            },
            [](Box a, const Box& b) {
                if (!b.empty()) {
                    a.add(b.lo);
                    a.add(b.hi);
                }
                return a;
            });
    }

    // ---- The light pass.

    // Whether the sample can light r at all (before shadows), or give it translucency.
    bool reaches(const LightSample& s, const Receiver& r) const {
        if (r.kind == Kind::kNone) return false;
        Vec3 wi;
        RGB E;
        if (!incident_light(s, r.p, wi, E)) return false;
        const double c = dot(r.ns, wi);
        if (c > 0) return true;
        return r.kind == Kind::kMedium && (s.thickness_view || slab_of(r.material) != nullptr);
    }
    // Whether the sample reaches any receiver.
    bool reaches_any(const LightSample& s) const {
        return tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, N, 4096), false,
            [&](const tbb::blocked_range<std::size_t>& br, bool acc) {
                for (std::size_t i = br.begin(); i != br.end() && !acc; ++i)
                    if (kind[i] != Kind::kNone)
                        acc = reaches(
                            s, receiver_at(i, static_cast<int>(i % W), static_cast<int>(i / W)));
                return acc;
            },
            [](bool a, bool b) { return a || b; });
    }

    // What a lit diffuse sample i of material m reflects (Lambert) of irradiance E at normal
    // incidence arriving at cosine cs > 0.
    void add_diffuse(int m, const RGB& E, double cs, std::size_t i) {
        const RGB& a = albedo_pi[static_cast<std::size_t>(m)];
        for (std::size_t c = 0; c < 3; ++c)
            g.surface[3 * i + c] += static_cast<float>(a[c] * E[c] * cs);
    }
    // What a lit medium sample i receives from direction wi (irradiance E at normal
    // incidence, cosine cs > 0 to its normal): the irradiance transmitted through its boundary
    // and, for a rough one, the GGX reflection towards the camera.
    void add_medium(const Receiver& r, const Vec3& wi, const RGB& E, double cs, std::size_t i) {
        const BoundaryTransmittance& T = *mat_T[static_cast<std::size_t>(r.material)];
        const double t = T(cs);
        for (std::size_t c = 0; c < 3; ++c)
            g.irradiance[3 * i + c] += static_cast<float>(t * E[c] * cs);
        if (T.alpha() > 0) {
            Vec3 bs, bt;
            basis(r.n, bs, bt);
            auto local = [&](const Vec3& v) { return Vec3{dot(v, bs), dot(v, bt), dot(v, r.n)}; };
            const double f = dielectric::rough_dielectric_f(
                local(r.wo), local(wi), T.eta(), T.alpha(), dielectric::TransportMode::kRadiance);
            for (std::size_t c = 0; c < 3; ++c)
                g.specular[3 * i + c] += static_cast<float>(f * cs * E[c]);
        }
    }

    // Cube faces: a receiver belongs to the first face it projects into, found once per
    // light sample (kNoFace: none), so that each face's pass skips the others' receivers.
    void assign_faces(const std::vector<ShadowView>& views) {
        face.resize(N);
        tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& rows) {
            for (int sy = rows.begin(); sy != rows.end(); ++sy)
                for (int sx = 0; sx < W; ++sx) {
                    const std::size_t i = frame.sample_index(sx, sy);
                    face[i] = kNoFace;
                    if (kind[i] == Kind::kNone) continue;
                    const std::size_t k = first_view(views, receiver_at(i, sx, sy).p);
                    if (k < views.size()) face[i] = static_cast<std::uint8_t>(k);
                }
        });
    }

    // The common case (a delta or sun direction, a direction of the environment, one
    // orthographic view, shadows on, no thickness, no slab tables, no sphere lights): the shadow
    // tests of a row at once (directional_row), then what the lit samples receive.
    void light_directional(const LightSample& s, const ShadowView& view,
                           const ShadowView::Projection& proj) {
        DirectionalRow k;
        k.camera = camera.position;
        k.forward = rays.forward;
        k.right = rays.right;
        k.up = rays.up;
        k.w = s.w;
        k.proj = proj;
        const double texel = view.texel_size(0.0);  // orthographic: any depth
        k.offset = o.normal_offset_texels * texel;
        k.bias = o.depth_bias_texels * texel;
        k.size = view.size;
        tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& rows) {
            static thread_local std::vector<double> cos_tl;
            static thread_local std::vector<std::uint8_t> lit_tl;
            cos_tl.resize(static_cast<std::size_t>(W));
            lit_tl.resize(static_cast<std::size_t>(W));
            for (int sy = rows.begin(); sy != rows.end(); ++sy) {
                const std::size_t row = frame.sample_index(0, sy);
                directional_row(k, W, rays.ndc_x.data(), rays.ndc_y[static_cast<std::size_t>(sy)],
                                &frame.view_z[row], &g.normal[3 * row], &kind[row], sm.depth.data(),
                                cos_tl.data(), lit_tl.data());
                for (int sx = 0; sx < W; ++sx) {
                    const std::size_t i = row + static_cast<std::size_t>(sx);
                    const double cs = cos_tl[static_cast<std::size_t>(sx)];
                    if (kind[i] == Kind::kNone || !(cs > 0) ||
                        !lit_tl[static_cast<std::size_t>(sx)])
                        continue;
                    const RGB& E = s.value;
                    if (kind[i] == Kind::kDiffuse) {
                        add_diffuse(g.material[i], E, cs, i);
                    } else {
                        add_medium(receiver_at(i, sx, sy), s.w, E, cs, i);
                    }
                }
            }
        });
    }

    // What light sample s gives receiver i = (sx, sy) through view `view` (projection `proj`,
    // its map in sm where need_map): the thickness layer, the light of a lit side, the
    // translucency of a medium lit from behind.
    void light_receiver(const LightSample& s, const ShadowView& view,
                        const ShadowView::Projection& proj, bool need_map, std::size_t i, int sx,
                        int sy) {
        const Receiver r = receiver_at(i, sx, sy);
        Vec3 wi;
        RGB E;
        if (!incident_light(s, r.p, wi, E)) return;
        const double cs = dot(r.ns, wi);
        // The point's map coordinates, once for both lookups below.
        const ClipVertex pc = need_map ? proj.at(r.p) : ClipVertex{};
        // Thickness along the light's ray from the map's first hit, if that is
        // the receiver's own shape [Jimenez10].
        double d_thick = -1;
        if (r.kind == Kind::kMedium && need_map &&
            (s.thickness_view || (cs < 0 && slab_of(r.material)))) {
            const ShadowMap::Lookup lk = sm.lookup(pc, r.p, true);
            if (lk.inside && lk.shape == r.shape && std::isfinite(lk.map_depth))
                d_thick =
                    std::max(0.0, lk.point_depth - lk.map_depth_smooth) * lk.distance_per_depth;
        }
        if (s.thickness_view) g.thickness[i] = static_cast<float>(std::max(0.0, d_thick));
        if (!s.lights) return;
        if (cs > 0) {
            bool lit = true;
            if (o.shadows) lit = lit_in_map(sm, view, proj, pc, r.n, wi, o);
            if (!lit || (!spheres.empty() && behind_sphere(plan->lights, spheres, s, r.p, wi)))
                return;
            if (r.kind == Kind::kDiffuse) {
                add_diffuse(r.material, E, cs, i);
            } else {
                add_medium(r, wi, E, cs, i);
            }
        } else if (r.kind == Kind::kMedium && d_thick >= 0) {
            if (const SlabTransmittance* st = slab_of(r.material)) {
                const auto Ts = st->at(d_thick * scene.unit_mm);
                for (std::size_t c = 0; c < 3; ++c)
                    g.translucency[3 * i + c] += static_cast<float>(E[c] * (-cs) * Ts[c]);
            }
        }
    }

    // View vi of light sample s: its shadow map (need_map), then what it gives the receivers
    // (light_directional where that applies, light_receiver per receiver of the view).
    void light_view(const LightSample& s, const std::vector<ShadowView>& views, std::size_t vi,
                    bool need_map) {
        using clock = std::chrono::steady_clock;
        if (need_map) {
            const auto t0 = clock::now();
            render_shadow_map(scene, views[vi], sm);
            shadow_ms += std::chrono::duration<double, std::milli>(clock::now() - t0).count();
            ++maps;
        }
        const ShadowView::Projection proj = views[vi].projection();
        const bool ortho = views[vi].orthographic;
        if (s.directional && s.lights && views.size() == 1 && ortho && o.shadows &&
            !s.thickness_view && !any_slab && spheres.empty()) {
            light_directional(s, views[vi], proj);
            return;
        }
        tbb::parallel_for(tbb::blocked_range<int>(0, H, std::max(1, 1024 / W)),
                          [&](const tbb::blocked_range<int>& rows) {
                              for (int sy = rows.begin(); sy != rows.end(); ++sy)
                                  for (int sx = 0; sx < W; ++sx) {
                                      const std::size_t i = frame.sample_index(sx, sy);
                                      if (kind[i] == Kind::kNone) continue;
                                      if (views.size() > 1 && face[i] != vi) continue;
                                      light_receiver(s, views[vi], proj, need_map, i, sx, sy);
                                  }
                          });
    }

    // The light samples of `light_plan` in order, each one's views in turn (a sample that
    // reaches no receiver renders no map).
    void light_pass(const LightPlan& light_plan) {
        plan = &light_plan;
        spheres = sphere_lights(light_plan.lights);
        any_slab = any_slab_table(slabs);
        for (const LightSample& s : light_plan.samples) {
            if (!reaches_any(s)) continue;
            const std::vector<ShadowView> views = light_plan.views(s, o);
            const bool need_map = o.shadows || s.thickness_view || any_slab;
            if (views.size() > 1) assign_faces(views);
            for (std::size_t vi = 0; vi < views.size(); ++vi) light_view(s, views, vi, need_map);
        }
    }
};

}  // namespace

void shade(const Scene& scene, const RasterCamera& camera, const RasterFrame& frame,
           const LightingOptions& o, const std::vector<SlabTransmittance>& slabs,
           LightingStats* stats, GBuffer& out) {
    using clock = std::chrono::steady_clock;
    const auto t_start = clock::now();
    check_lighting_inputs(camera, frame, o);
    ShadePass pass(scene, camera, frame, o, slabs, out);
    // The scene's lights resolved once (core/light.h): what the receiver pass's rays see of
    // them, then the plan's (LightPlan::lights) for the light pass.
    std::vector<Light> lights(scene.lights.begin(), scene.lights.end());
    const Box receivers = pass.receiver_pass(lights);
    const LightPlan plan = plan_lights(scene, receivers, o, std::move(lights));
    pass.light_pass(plan);

    if (stats) {
        stats->shadow_maps = pass.maps;
        stats->light_samples = static_cast<int>(plan.samples.size());
        stats->shadow_ms = pass.shadow_ms;
        stats->shading_ms =
            std::chrono::duration<double, std::milli>(clock::now() - t_start).count() -
            pass.shadow_ms;
    }
}

std::vector<std::array<double, 3>> boundary_irradiance(const Scene& scene,
                                                       const std::vector<BoundaryPoint>& points,
                                                       const LightingOptions& o,
                                                       const Box& receivers, LightingStats* stats) {
    using clock = std::chrono::steady_clock;
    const auto t_start = clock::now();
    const std::size_t n = points.size();
    std::vector<std::array<double, 3>> E(n, RGB{});
    check_lighting_options(o);
    Box box;
    for (std::size_t i = 0; i < n; ++i) {
        const BoundaryPoint& q = points[i];
        if (q.material < 0 || static_cast<std::size_t>(q.material) >= scene.materials.size() ||
            scene.materials[static_cast<std::size_t>(q.material)].kind !=
                SceneMaterial::Kind::kMedium)
            throw std::invalid_argument("boundary_irradiance: point " + std::to_string(i) +
                                        " is not on a medium");
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(q.p[c]) || !std::isfinite(q.n[c]))
                throw std::invalid_argument("boundary_irradiance: point " + std::to_string(i) +
                                            " is not finite");
        box.add(q.p);
    }
    if (n == 0) return E;
    const std::vector<const BoundaryTransmittance*> mat_T = boundary_tables(scene, o);
    const LightPlan plan = plan_lights(scene, receivers.empty() ? box : receivers, o);
    const std::vector<int> spheres = sphere_lights(plan.lights);
    static thread_local ShadowMap scratch_map;
    ShadowMap& sm = scratch_map;
    std::vector<std::uint8_t> face(n, 0);
    double shadow_ms = 0;
    int maps = 0;
    for (const LightSample& s : plan.samples) {
        if (!s.lights) continue;
        const std::vector<ShadowView> views = plan.views(s, o);
        if (views.size() > 1)
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  for (std::size_t i = r.begin(); i != r.end(); ++i)
                                      face[i] = static_cast<std::uint8_t>(std::min<std::size_t>(
                                          first_view(views, points[i].p), 255));
                              });
        for (std::size_t vi = 0; vi < views.size(); ++vi) {
            if (o.shadows) {
                const auto t0 = clock::now();
                render_shadow_map(scene, views[vi], sm);
                shadow_ms += std::chrono::duration<double, std::milli>(clock::now() - t0).count();
                ++maps;
            }
            const ShadowView::Projection proj = views[vi].projection();
            tbb::parallel_for(
                tbb::blocked_range<std::size_t>(0, n, 1024),
                [&](const tbb::blocked_range<std::size_t>& r) {
                    for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        if (views.size() > 1 && face[i] != vi) continue;
                        const BoundaryPoint& q = points[i];
                        Vec3 wi;
                        RGB Ei;
                        if (!incident_light(s, q.p, wi, Ei)) continue;
                        const double cs = dot(q.n, wi);
                        if (!(cs > 0)) continue;
                        if (o.shadows && !lit_in_map(sm, views[vi], proj, proj.at(q.p), q.n, wi, o))
                            continue;
                        if (!spheres.empty() && behind_sphere(plan.lights, spheres, s, q.p, wi))
                            continue;
                        const double t = (*mat_T[static_cast<std::size_t>(q.material)])(cs);
                        for (std::size_t c = 0; c < 3; ++c) E[i][c] += t * Ei[c] * cs;
                    }
                });
        }
    }
    if (stats) {
        stats->shadow_maps = maps;
        stats->light_samples = static_cast<int>(plan.samples.size());
        stats->shadow_ms = shadow_ms;
        stats->shading_ms =
            std::chrono::duration<double, std::milli>(clock::now() - t_start).count() - shadow_ms;
    }
    return E;
}

}  // namespace ssslab::realtime
