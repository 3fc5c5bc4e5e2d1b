// Rough dielectric boundary: the GGX microfacet model for reflection and transmission
// [Walter et al. 2007, "Microfacet models for refraction through rough surfaces"], with the
// height-correlated Smith masking-shadowing term and sampling of the visible normals
// [Heitz 2018, "Sampling the GGX distribution of visible normals"], as pbrt-v4's rough
// DielectricBxDF does. Directions are in the local frame of the macro-surface (normal +z) and
// point away from the surface; `eta` is the index below (-z side) over the index above.
//
// Transport modes: kRadiance for paths from the camera (the transmitted radiance carries
// 1 / eta'^2, radiance compression across the boundary), kImportance for paths from the light
// (no such factor). Single scattering between microfacets only: the albedo falls below 1 as
// the roughness grows (a few percent at alpha = 0.3, ~10-20 % at alpha = 1).
#pragma once

#include "core/dielectric.h"
#include "core/vec3.h"
#include "volpath/sampling.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace ssslab::volpath {

// The model itself (D, Lambda, G1, G, f) is core/dielectric.h's, shared with realtime/; the
// names stay here so that volpath's code reads as before.
using dielectric::TransportMode;

namespace ggx {

using dielectric::ggx::cos2_theta;
using dielectric::ggx::D;
using dielectric::ggx::G;
using dielectric::ggx::G1;
using dielectric::ggx::lambda;
using dielectric::ggx::tan2_theta;

/// Density of the visible normals from w: G1(w) max(0, w.m) D(m) / |cos theta_w|.
inline double D_visible(const Vec3& w, const Vec3& m, double alpha) {
    return G1(w, alpha) / std::abs(w.z) * D(m, alpha) * std::abs(dot(w, m));
}
/// A visible normal for w (Heitz 2018): on the hemisphere of +z, distributed as D_visible.
inline Vec3 sample_visible_normal(const Vec3& w, double alpha, double u1, double u2) {
    Vec3 wh = normalize(Vec3{alpha * w.x, alpha * w.y, w.z});
    if (wh.z < 0) wh = -wh;
    const Vec3 t1 = wh.z < 0.99999 ? normalize(cross(Vec3{0, 0, 1}, wh)) : Vec3{1, 0, 0};
    const Vec3 t2 = cross(wh, t1);
    // Uniform point on the unit disc (polar), then warped onto the projected hemisphere.
    const double r = std::sqrt(u1), phi = 2 * kPi * u2;
    double px = r * std::cos(phi), py = r * std::sin(phi);
    const double h = std::sqrt(std::max(0.0, 1 - px * px));
    const double s = 0.5 * (1 + wh.z);
    py = (1 - s) * h + s * py;
    const double pz = std::sqrt(std::max(0.0, 1 - px * px - py * py));
    const Vec3 nh = t1 * px + t2 * py + wh * pz;
    return normalize(Vec3{alpha * nh.x, alpha * nh.y, std::max(1e-12, nh.z)});
}

}  // namespace ggx

using dielectric::fresnel_signed;

struct BsdfSample {
    Vec3 wi;
    double f = 0;    ///< BSDF value [1/sr]
    double pdf = 0;  ///< solid-angle density of wi
    bool reflection = false;
};

using dielectric::microfacet_pair;
using dielectric::MicrofacetPair;
using dielectric::rough_dielectric_f;

/// The density sample_rough_dielectric draws wi with, for wo.
inline double rough_dielectric_pdf(const Vec3& wo, const Vec3& wi, double eta, double alpha) {
    const auto mp = microfacet_pair(wo, wi, eta);
    if (!mp) return 0;
    const Vec3& wm = mp->wm;
    const double R = fresnel_signed(dot(wo, wm), eta), T = 1 - R;
    // Visible normals are sampled for the side wo is on.
    const Vec3 wo_up = wo.z > 0 ? wo : -wo;
    const double dv = ggx::D_visible(wo_up, wm, alpha);
    if (mp->reflect) return dv / (4 * std::abs(dot(wo, wm))) * R;
    const double d = dot(wi, wm) + dot(wo, wm) / mp->etap;
    return dv * std::abs(dot(wi, wm)) / (d * d) * T;
}

/// Sample wi for wo: a visible microfacet normal, then reflection with probability F(wo . m)
/// or refraction. Empty when the sampled direction is invalid (below the surface after a
/// reflection, or on the same side after a refraction): the path ends there.
inline std::optional<BsdfSample> sample_rough_dielectric(const Vec3& wo, double eta, double alpha,
                                                         double uc, double u1, double u2,
                                                         TransportMode mode) {
    if (wo.z == 0) return std::nullopt;
    const Vec3 wo_up = wo.z > 0 ? wo : -wo;
    Vec3 wm = ggx::sample_visible_normal(wo_up, alpha, u1, u2);
    if (wo.z < 0) wm = -wm;             // the microfacet normal on wo's side
    const double cos_om = dot(wo, wm);  // > 0
    const double eta_side = wo.z > 0 ? eta : 1.0 / eta;
    double cos_t = 0;
    const double R = fresnel_dielectric(std::abs(cos_om), eta_side, cos_t);
    BsdfSample s;
    if (uc < R) {
        s.wi = wm * (2 * cos_om) - wo;
        if (s.wi.z * wo.z <= 0) return std::nullopt;
        s.reflection = true;
    } else {
        // Refraction of -wo through the microfacet (normal wm on wo's side).
        s.wi = normalize(-wo * (1.0 / eta_side) + wm * (cos_om / eta_side - cos_t));
        if (s.wi.z * wo.z >= 0) return std::nullopt;
    }
    s.f = rough_dielectric_f(wo, s.wi, eta, alpha, mode);
    s.pdf = rough_dielectric_pdf(wo, s.wi, eta, alpha);
    if (!(s.pdf > 0) || !(s.f > 0)) return std::nullopt;
    return s;
}

}  // namespace ssslab::volpath
