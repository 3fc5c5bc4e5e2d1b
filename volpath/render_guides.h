// The path tracer's guides (volpath/render_guides.cpp): the data of the exit guide behind rough
// boundaries (ExitGuide: at scattering vertices, volpath-render-8, and at the boundary's own
// vertices, volpath-render-9), the share a guide takes in the MIS weights at the exit it aims at
// (GuideShare, share_of), and the diffuse guide of a vertex straight after the way out of a
// guided medium (DiffuseGuide, volpath-render-10), with the medium and surface data they read.
// The renderer's functions that aim and run them (Renderer::exit_guide, guided_exits,
// arrival_share, boundary_guide, diffuse_guide, diffuse_guided, run_diffuse_guide) are in
// render_guides.cpp; run_exit_guide, the coin drawn at every scattering vertex of a guided medium,
// is inline in renderer.h, as is the shadow ray they share with NEE (Renderer::reaches).
// Internal to the renderer: included by renderer.h, render.cpp and render_guides.cpp only.
#pragma once

#include "core/light.h"
#include "core/vec3.h"
#include "volpath/density_grid.h"
#include "volpath/embree_scene.h"
#include "volpath/microfacet.h"
#include "volpath/sampling.h"
#include "volpath/walk.h"

#include <array>
#include <memory>
#include <vector>

namespace ssslab::volpath::render_detail {

using RGB = std::array<double, 3>;

struct MediumData {
    RGB sigma_t{}, sigma_s{}, g{};  // per world unit (scaled by the density, if any)
    bool same_g = true;
    double eta = 1, alpha = 0;
    Absorption absorption = Absorption::kAnalog;  // of its walks (render_absorption)
    bool guided = false;  // its walks' scattering vertices have exit guides (exit_guide)
    std::shared_ptr<const DensityGrid> density;  // heterogeneous media (OpenVDB)
    WalkRegion region;                           // the walk's view of the above
};

// A surface vertex as NEE sees it: the normal of the side lit and the triangle it lies on.
struct SurfaceAt {
    Vec3 n;
    TriangleRef triangle;
};

inline double power(double a, double b) {
    return a * a / (a * a + b * b);
}

// The exit guide (RenderOptions::exit_guide) aims from a vertex whose way out towards a light
// is at most kExitGuideReach of the medium's smallest mean free paths long, and its estimator
// runs at such a vertex with probability kExitGuideProb (its MIS density is scaled by it). Chosen
// on the built-in scenes at 48 x 48 (wholemilk, 1,536 spp: reach 3, 5, 8, 12, 20 and
// probability 1/16 to 1): beyond 8 the image variance fell little for the time, and at 1/4
// the estimator costs wholemilk about a fifth of its time where every vertex cost half.
constexpr double kExitGuideReach = 8.0;
constexpr double kExitGuideProb = 0.25;
constexpr int kMaxGuides = 4;  // guide lights (sphere lights and sun discs) a vertex aims at
constexpr int kMaxLobes = 2 * kMaxGuides;  // an exit guide's lobes: a narrow and a wide per light
// The wide lobe's spread (radians) beside each narrow one. Chosen on ketchup at 128 x 128, 768 spp
// (seeds 4-7): the bumpy blob's summed SE^2 31.8-41.6 without, 7.2-9.7 with 0.3.
constexpr double kWideLobeSpread = 0.3;
// A diffuse vertex's guide lobe (DiffuseGuide) runs with this probability, and its aim corrects
// the direction through the medium's two boundaries this many times.
constexpr double kDiffuseGuideProb = 0.5;
constexpr int kDiffuseGuideAims = 2;

// The exit guide of a vertex z from which a walk inside a medium behind a rough boundary goes on
// in a sampled direction: a scattering vertex (the phase function's direction), or since
// volpath-render-9 a vertex on that boundary (the rough BSDF's direction into the medium: the
// entry from outside, an internal reflection). Per guide light, a von Mises-Fisher lobe of
// directions from z about the one the boundary refracts towards the light, and what the walk's
// own density of reaching the boundary needs.
struct ExitGuide {
    bool aimed = false;  // the lobes below are those of z (computed when first needed)
    int n = 0;           // lobes (0: no guide at z)
    int light[kMaxLobes] = {};
    Vec3 axis[kMaxLobes];
    double kappa[kMaxLobes] = {};
    Vec3 z, din;                 // the vertex and the direction the path arrived along
    std::array<double, 3> pq{};  // P(k) q_k at z, the hero mixture's weights (they sum to one)
    // On the boundary (z on triangle tri, its outward normal normal): the walk's direction
    // comes from the rough BSDF for the incident direction -din.
    bool surface = false;
    Vec3 normal;
    TriangleRef tri;
    // The guide (not yet aimed) of boundary vertex z, reached along din, for the hero mixture pq.
    static ExitGuide on_boundary(const Vec3& z, const Vec3& din, const Vec3& normal,
                                 TriangleRef tri, const std::array<double, 3>& pq) {
        ExitGuide g;
        g.surface = true;
        g.z = z;
        g.din = din;
        g.normal = normal;
        g.tri = tri;
        g.pq = pq;
        return g;
    }
    // The vertex's value for direction w (the phase function, or the BSDF times |cos|) and
    // the density with which the walk samples w there.
    double value(const MediumData& md, const Vec3& w) const {
        if (!surface) return hg_pdf(md.g[0], dot(din, w));
        const Frame fr(normal);
        const Vec3 wi = fr.local(w);
        return rough_dielectric_f(fr.local(-din), wi, md.eta, md.alpha, TransportMode::kRadiance) *
               std::abs(wi.z);
    }
    double pdf(const MediumData& md, const Vec3& w) const {
        if (!surface) return hg_pdf(md.g[0], dot(din, w));
        const Frame fr(normal);
        return rough_dielectric_pdf(fr.local(-din), fr.local(w), md.eta, md.alpha);
    }
    // Whether w goes from z into the medium (always from a scattering vertex).
    bool inward(const Vec3& w) const { return !surface || dot(w, normal) < 0; }
    // The walk's density of the way from z along w to the boundary at distance t in medium md:
    // the vertex's density of w times the hero mixture's probability of no collision before it.
    double walk_density(const MediumData& md, const Vec3& w, double t) const {
        double T = 0;
        for (std::size_t k = 0; k < 3; ++k) T += pq[k] * std::exp(-md.sigma_t[k] * t);
        return pdf(md, w) * T;
    }
    // The guide's density of direction w by lobe i: its estimator runs with probability
    // kExitGuideProb, then draws w from the lobe. `prob` is that probability, or at an entry
    // straight from a diffuse vertex with a guide (DiffuseGuide), that plus the diffuse guide's
    // density of din over the cosine's there: the ways to this guide's direction at z.
    double prob = kExitGuideProb;
    // Each lobe is a strategy of its own (one sample each), so the density of lobe i's light
    // is the sum over that light's lobes.
    double density(int i, const Vec3& w) const {
        double p = 0;
        for (int k = 0; k < n; ++k)
            if (light[k] == light[i]) p += prob * vmf_pdf(axis[k], kappa[k], w);
        return p;
    }
};

// What the exit guide adds to the densities of the strategies at the exit vertex x it aims at,
// per guide light: vmf(w) / walk_density(w, t) for the walk's arrival along w, times the
// light's own solid-angle density of the direction from x (the guide's NEE samples the light
// from x as NEE does). Lights it does not name keep the power heuristic.
struct GuideShare {
    int n = 0;
    const Light* light[kMaxGuides] = {};
    double factor[kMaxGuides] = {};
    double of(const Light* l) const {
        for (int i = 0; i < n; ++i)
            if (light[i] == l) return factor[i];
        return -1;
    }
    // The MIS weight of a strategy of density p against the other one's (other) and the
    // guide's (share x the light's density pl_light): balance where the guide takes part.
    double weight(const Light* l, double p, double other, double pl_light) const {
        const double f = of(l);
        return f < 0 ? power(p, other) : p / (p + other + f * pl_light);
    }
};

// The share of guide g (aimed, of a vertex in medium md) at the exit the walk reached from it
// along w at distance t.
inline GuideShare share_of(const ExitGuide& g, const MediumData& md,
                           const std::vector<Light>& lights, const Vec3& w, double t) {
    GuideShare share;
    const double wd = g.walk_density(md, w, t);
    for (int i = 0; i < g.n; ++i) {
        if (i > 0 && g.light[i] == g.light[i - 1]) continue;  // a light's lobes share one density
        share.light[share.n] = &lights[static_cast<size_t>(g.light[i])];
        share.factor[share.n] = wd > 0 ? g.density(i, w) / wd : 0.0;
        ++share.n;
    }
    return share;
}

// The guide of a diffuse vertex x that the path reached straight from the way out of a guided
// medium (volpath-render-10): light that reaches x through that medium from a guide light,
// crossing it without a collision (the caustic a thin puddle casts on what lies under it, seen
// through the puddle). Per guide light, a von Mises-Fisher lobe of directions from x about the
// one that the two boundaries (in, then out) refract towards the light; a direction from a lobe
// enters the medium, where the entry's exit guide (every lobe, no coin) estimates the light that
// leaves straight from there. One more strategy for those paths (x, the entry, the exit, the
// light), in the balance heuristic with the walk's (the cosine at x, then its ways to the exit)
// and the entry's exit guide after the cosine: ExitGuide::prob at that entry carries its density.
struct DiffuseGuide {
    int n = 0;  // lobes (0: none)
    Vec3 axis[kMaxGuides];
    double kappa[kMaxGuides] = {};
    // The lobes' density of direction w (each lobe's estimator runs with kDiffuseGuideProb).
    double density(const Vec3& w) const {
        double p = 0;
        for (int i = 0; i < n; ++i) p += kDiffuseGuideProb * vmf_pdf(axis[i], kappa[i], w);
        return p;
    }
};

}  // namespace ssslab::volpath::render_detail
