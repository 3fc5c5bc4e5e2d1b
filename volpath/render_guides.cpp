// The path tracer's guides (the data: volpath/render_guides.h), the Renderer's functions that aim
// and run them: the exit guide of a vertex inside a medium behind a rough boundary, aimed
// (Renderer::exit_guide) and run (guided_exits; run_exit_guide, inline in renderer.h, draws the
// coin at a scattering vertex, volpath-render-8), its share in the MIS at the exit a walk reaches
// straight from a guided vertex (arrival_share), the same guide at the boundary's own vertices
// from which a walk goes on inside (boundary_guide, volpath-render-9), and the diffuse guide of a
// vertex straight after the way out of a guided medium (diffuse_guide, diffuse_guided and
// run_diffuse_guide, volpath-render-10). The light sampling they share with NEE (Renderer::reaches,
// env_normal) is inline in renderer.h.
#include "volpath/render_guides.h"

#include "core/light.h"
#include "core/rng.h"
#include "core/vec3.h"
#include "volpath/embree_scene.h"
#include "volpath/microfacet.h"
#include "volpath/renderer.h"
#include "volpath/sampling.h"
#include "volpath/walk.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace ssslab::volpath::render_detail {

// The exit guide at vertex g.z of a guided medium md inside `shape` (a scattering vertex, or
// one on its boundary from which the walk goes inwards): per guide light whose direction
// from the vertex (inwards from a boundary vertex; towards a sphere's
// centre, along a disc's axis) leaves the shape within kExitGuideReach of md's smallest
// mean free paths, the inside direction that the boundary there refracts along it, and a
// concentration from the light's angular radius (shrunk by the refraction) and the spread
// of refracted directions over GGX normals of width alpha. A vertex whose ball
// (SurfaceDistanceGrid) is wider than the reach has none, without a query.
void Renderer::exit_guide(const MediumData& md, int shape, ExitGuide& g,
                          std::uint64_t& rays) const {
    g.aimed = true;
    g.n = 0;
    const double sigma_min = std::min({md.sigma_t[0], md.sigma_t[1], md.sigma_t[2]});
    if (!(sigma_min > 0)) return;
    const double reach = kExitGuideReach / sigma_min;
    if (!shape_balls.empty()) {
        if (const auto* balls = shape_balls[static_cast<size_t>(shape)].get()) {
            Vec3 c;
            double r = 0;
            if (balls->ball(g.z, c, r) && r - length(g.z - c) > reach) return;
        }
    }
    const double eta = md.eta;
    const double spread_rough = 1.5 * md.alpha * std::abs(1 - 1 / eta);
    for (int j : guide_lights) {
        Vec3 to;
        double angle = 0;
        if (!lights[static_cast<size_t>(j)].cone(g.z, to, angle) || !g.inward(to)) continue;
        ++rays;
        const RayHit hit = es->intersect(g.z, to, 0, reach, g.tri);
        if (!hit.hit() || hit.shape != static_cast<std::uint32_t>(shape)) continue;
        const Vec3& n = hit.normal;
        const double cn = dot(to, n);
        if (!(cn > 0)) continue;
        Vec3 inside;  // the inside direction that leaves along `to`
        if (!snell(to, n, 1 / eta, inside)) continue;
        const double spread = std::max(0.01, std::hypot(angle / eta, spread_rough));  // radians
        g.light[g.n] = j;
        g.axis[g.n] = normalize(inside);
        g.kappa[g.n] = std::min(1e5, 1 / (spread * spread));
        ++g.n;
        // A wide lobe about the same axis (volpath-render-11): where the boundary's normal
        // varies over the lobe's footprint (a bumpy surface), the narrow lobe aims through
        // one exit point's normal and misses the others that refract towards the light.
        if (opt.wide_lobes) {
            g.light[g.n] = j;
            g.axis[g.n] = g.axis[g.n - 1];
            g.kappa[g.n] = 1 / (kWideLobeSpread * kWideLobeSpread);
            ++g.n;
        }
    }
}

// The exit guide's estimator at its vertex (weights bs, before the vertex's value, which it
// evaluates for its own direction: ExitGuide::value): per lobe, a direction from it, the
// flight to the boundary without a collision (the transmittance a weight), NEE of the lobe's
// light through the rough boundary there; balance heuristic against the walk's own ways to
// the same path (its flight, then NEE or BSDF sampling at the exit).
void Renderer::guided_exits(const ExitGuide& g, const MediumData& md, int shape, const double* bs,
                            RngStream& rng, RGB& out, std::uint64_t& rays) const {
    for (int i = 0; i < g.n; ++i) {
        // From the stream, not a Sobol dimension: the walk's own numbers keep their pairs.
        const double u1 = rng.stream_uniform(), u2 = rng.stream_uniform(),
                     u3 = rng.stream_uniform(), u4 = rng.stream_uniform();
        const Vec3 w = sample_vmf(g.axis[i], g.kappa[i], u1, u2);
        if (!g.inward(w)) continue;
        ++rays;
        const RayHit hit = es->intersect(g.z, w, 0, kInf, g.tri);
        if (!hit.hit() || hit.shape != static_cast<std::uint32_t>(shape) ||
            !(dot(w, hit.normal) > 0))
            continue;
        const Vec3 x = g.z + w * hit.t;
        const SurfaceAt at{hit.normal, {hit.shape, hit.triangle}};
        const Light& light = lights[static_cast<size_t>(g.light[i])];
        const LightSample ls = light.sample(x, u3, u4, env_normal(&at.n));
        if (!ls.ok || !(ls.pdf > 0) || !(dot(ls.wi, at.n) > 0)) continue;
        const Frame fr(at.n);
        const Vec3 wo_l = fr.local(-w), wi_l = fr.local(ls.wi);
        const double f =
            rough_dielectric_f(wo_l, wi_l, md.eta, md.alpha, TransportMode::kRadiance) *
            std::abs(wi_l.z);
        if (!(f > 0)) continue;
        RGB T{1, 1, 1};
        if (!reaches(light, x, &at, ls, -1, T, rays)) continue;
        const double denom =
            g.walk_density(md, w, hit.t) *
                (sel * ls.pdf + rough_dielectric_pdf(wo_l, wi_l, md.eta, md.alpha)) +
            g.density(i, w) * ls.pdf;
        const double fz = g.value(md, w);
        for (std::size_t c = 0; c < 3; ++c)
            out[c] +=
                bs[c] * fz * std::exp(-md.sigma_t[c] * hit.t) * f * ls.value[c] * T[c] / denom;
    }
}

// The share in the MIS at exit vertex p, reached straight from the last vertex a walk went on
// from (c.guide, armed), of that vertex's exit guide: aimed if it was not (its coin did not run
// it), then share_of for the arrival along the path's direction.
GuideShare Renderer::arrival_share(CameraPath& c, const Vec3& p, const MediumData& md) const {
    if (!c.guide.aimed) exit_guide(md, c.medium_shape, c.guide, c.rays);
    return share_of(c.guide, md, lights, c.ws.w, length(p - c.guide.z));
}

// The exit guide of rough boundary vertex p (normal n, on triangle tri) of guided medium md
// (volpath-render-9), as at a scattering vertex: the light that crosses the medium from here to
// the way out without a collision, an estimator of its own whatever the walk's sample does after
// it (enter or go on inside, or not), its estimate flushed as subsurface light. Not where the
// exit it aims at would lie beyond max_depth. `here`: the guide, for the MIS of the exit the walk
// reaches straight from p; false where there is none.
bool Renderer::boundary_guide(CameraPath& c, const Vec3& p, const Vec3& n, TriangleRef tri,
                              const MediumData& md, bool outside, bool plate_arrival,
                              ExitGuide& here) const {
    const bool beyond = opt.max_depth > 0 && c.depth + 1 >= opt.max_depth;
    if (!md.guided || !opt.boundary_guides || beyond) return false;
    const Vec3& d = c.ws.w;
    // The hero mixture of the walk from here: the one inside, or the probabilities the
    // entry will choose the hero with.
    here = ExitGuide::on_boundary(
        p, d, n, tri, outside ? entry_probabilities(c.ws, md) : inside_probabilities(c.ws));
    // An entry straight from a diffuse vertex with a guide: that guide's lobes are one
    // more way to this guide's paths.
    if (plate_arrival && outside) {
        const double pc = std::max(0.0, dot(d, c.plate_n)) / kPi;
        if (pc > 0) here.prob += c.plate.density(d) / pc;
    }
    RGB g{};
    run_exit_guide(here, md, static_cast<int>(tri.shape), c.ws.weights.beta, c.rng, g, c.rays);
    flush(c, g, true);
    return true;
}

// The guide of diffuse vertex x (normal n, on triangle tri; DiffuseGuide): per guide light,
// the direction from x that, refracted into the guided medium it meets first and out of it
// again, leaves towards the light: the light's direction corrected kDiffuseGuideAims times
// by the difference between it and the way out found (exact for parallel boundaries, close
// for a thin medium's). The lobe's width: the light's angular radius and the spread that
// GGX normals of width alpha give each refraction (both 1.5 alpha |eta - 1| outside).
void Renderer::diffuse_guide(const Vec3& x, const Vec3& n, TriangleRef tri, DiffuseGuide& g,
                             std::uint64_t& rays) const {
    g.n = 0;
    for (int j : guide_lights) {
        Vec3 to;
        double angle = 0;
        if (!lights[static_cast<size_t>(j)].cone(x, to, angle)) continue;
        Vec3 a = to;
        const MediumData* md = nullptr;
        for (int it = 0; it < kDiffuseGuideAims; ++it) {
            md = nullptr;
            if (!(dot(a, n) > 0)) break;
            ++rays;
            const RayHit in = es->intersect(x, a, 0, kInf, tri);
            if (!in.hit()) break;
            const int mi = shape_medium[in.shape];
            if (mi < 0 || !media[static_cast<size_t>(mi)].guided) break;
            const MediumData& m = media[static_cast<size_t>(mi)];
            const double c1 = dot(a, in.normal);
            if (!(c1 < 0)) break;
            Vec3 b;  // a refracted in
            if (!snell(a, in.normal, 1 / m.eta, b)) break;
            ++rays;
            const RayHit out = es->intersect(x + a * in.t, b, 0, kInf, {in.shape, in.triangle});
            if (!out.hit() || out.shape != in.shape) break;
            const double c2 = dot(b, out.normal);
            if (!(c2 > 0)) break;
            Vec3 c;  // b refracted out
            if (!snell(b, out.normal, m.eta, c)) break;
            a = normalize(a + (to - c));
            md = &m;
        }
        if (!md || !(dot(a, n) > 0)) continue;
        const double rough = 1.5 * md->alpha * std::abs(md->eta - 1);
        const double spread = std::max(0.01, std::hypot(angle, rough, rough));
        g.axis[g.n] = a;
        g.kappa[g.n] = std::min(1e5, 1 / (spread * spread));
        ++g.n;
    }
}

// The diffuse guide's estimator at x (the path's weights ws after x's albedo, i.e. times
// the diffuse BSDF's value over the cosine's density): per lobe, with probability
// kDiffuseGuideProb, a direction w from it; where w meets a guided medium from outside, the
// entry's exit guide, every lobe, its density (ExitGuide::prob) that of all the ways to w at x
// over the cosine's. An entry beyond max_depth (the diffuse vertex at `depth`, the entry next)
// adds nothing.
void Renderer::diffuse_guided(const DiffuseGuide& g, const Vec3& x, const Vec3& n, TriangleRef tri,
                              const WalkState<3>& ws, int depth, RngStream& rng, RGB& out,
                              std::uint64_t& rays) const {
    const bool beyond = opt.max_depth > 0 && depth + 2 >= opt.max_depth;
    for (int i = 0; i < g.n; ++i) {
        const double u0 = rng.stream_uniform(), u1 = rng.stream_uniform(),
                     u2 = rng.stream_uniform();
        if (beyond || !(u0 < kDiffuseGuideProb)) continue;
        const Vec3 w = sample_vmf(g.axis[i], g.kappa[i], u1, u2);
        const double cs = dot(w, n);
        if (!(cs > 0)) continue;
        ++rays;
        const RayHit hit = es->intersect(x, w, 0, kInf, tri);
        if (!hit.hit()) continue;
        const int mi = shape_medium[hit.shape];
        if (mi < 0) continue;
        const MediumData& md = media[static_cast<size_t>(mi)];
        if (!md.guided || !(dot(w, hit.normal) < 0)) continue;
        ExitGuide e = ExitGuide::on_boundary(
            x + w * hit.t, w, hit.normal, {hit.shape, hit.triangle}, entry_probabilities(ws, md));
        exit_guide(md, static_cast<int>(hit.shape), e, rays);
        if (e.n == 0) continue;
        e.prob = kExitGuideProb + g.density(w) / (cs / kPi);
        guided_exits(e, md, static_cast<int>(hit.shape), ws.weights.beta, rng, out, rays);
    }
}

// The diffuse guide of diffuse vertex p (its normal n on the side of the path's arrival, on
// triangle tri), which the path reached straight from a guided medium's way out
// (volpath-render-10; with diffuse_guides, boundary_guides and rays_from_surface): aimed, run
// (its estimate flushed as subsurface light) and armed for the entry the path meets next.
void Renderer::run_diffuse_guide(CameraPath& c, const Vec3& p, const Vec3& n,
                                 TriangleRef tri) const {
    if (!(opt.diffuse_guides && opt.boundary_guides && opt.rays_from_surface)) return;
    diffuse_guide(p, n, tri, c.plate, c.rays);
    if (c.plate.n > 0) {
        RGB g{};
        diffuse_guided(c.plate, p, n, tri, c.ws, c.depth, c.rng, g, c.rays);
        flush(c, g, true);
        c.plate_n = n;
        c.plate_armed = true;
    }
}

}  // namespace ssslab::volpath::render_detail
