// Dielectric boundary optics shared by the path tracer (volpath/) and the real-time renderer
// (realtime/), so that both shade the same boundary with one copy of each formula: the exact
// unpolarised Fresnel reflectance of a smooth interface, and the GGX microfacet model of a rough
// one [Walter et al. 2007, "Microfacet models for refraction through rough surfaces"] with the
// height-correlated Smith masking-shadowing term, as pbrt-v4's rough DielectricBxDF. Directions
// are in the local frame of the macro-surface (normal +z) and point away from the surface; `eta`
// is the index below (-z side) over the index above. Sampling (visible normals) stays with the
// path tracer (volpath/microfacet.h). mcml/ keeps its own Fresnel (an independent witness).
#pragma once

#include "core/vec3.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

namespace ssslab::dielectric {

/// Unpolarised Fresnel reflectance of a smooth dielectric interface for light arriving with
/// cosine cos_i >= 0 to the normal, eta = n_transmitted / n_incident (any positive ratio; 1 gives
/// exactly 0). Total internal reflection gives 1. Also returns the cosine of the refracted ray.
inline double fresnel_dielectric(double cos_i, double eta, double& cos_t) {
    cos_i = std::min(cos_i, 1.0);
    const double sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0) {
        cos_t = 0.0;
        return 1.0;
    }
    cos_t = std::sqrt(1.0 - sin2_t);
    if (eta == 1.0) return 0.0;
    const double rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    const double rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}
inline double fresnel_dielectric(double cos_i, double eta) {
    double cos_t;
    return fresnel_dielectric(cos_i, eta, cos_t);
}

/// Fresnel reflectance for a cosine of either sign against the normal of the side the light
/// comes from (negative: from below, where the relative index is 1 / eta).
inline double fresnel_signed(double cos_i, double eta) {
    return cos_i >= 0 ? fresnel_dielectric(cos_i, eta) : fresnel_dielectric(-cos_i, 1.0 / eta);
}

/// Transport modes: kRadiance for paths from the camera (the transmitted radiance carries
/// 1 / eta'^2, radiance compression across the boundary), kImportance for paths from the light
/// (no such factor).
enum class TransportMode { kRadiance, kImportance };

namespace ggx {

inline double cos2_theta(const Vec3& w) {
    return w.z * w.z;
}
inline double tan2_theta(const Vec3& w) {
    const double c2 = cos2_theta(w);
    return std::max(0.0, 1.0 - c2) / c2;
}

/// D(m): microfacet normals per unit projected area, isotropic roughness alpha;
/// integral of D(m) cos(theta_m) over the hemisphere is 1 [Walter et al. 2007, Eq. 33].
inline double D(const Vec3& m, double alpha) {
    const double t2 = tan2_theta(m);
    if (!std::isfinite(t2)) return 0;
    const double c4 = cos2_theta(m) * cos2_theta(m);
    const double e = 1 + t2 / (alpha * alpha);
    return 1.0 / (std::numbers::pi * alpha * alpha * c4 * e * e);
}
/// Smith's Lambda for GGX.
inline double lambda(const Vec3& w, double alpha) {
    const double t2 = tan2_theta(w);
    if (!std::isfinite(t2)) return 0;
    return 0.5 * (std::sqrt(1 + alpha * alpha * t2) - 1);
}
inline double G1(const Vec3& w, double alpha) {
    return 1.0 / (1.0 + lambda(w, alpha));
}
/// Height-correlated masking-shadowing.
inline double G(const Vec3& wo, const Vec3& wi, double alpha) {
    return 1.0 / (1.0 + lambda(wo, alpha) + lambda(wi, alpha));
}

}  // namespace ggx

/// The pair (wo, wi) seen by the microfacet that connects them: the generalized half vector
/// wm (on the +z side) of Walter et al. (eq. 16), etap = 1 for reflection, else the relative
/// index from wo's side. Empty when a direction is tangent, the pair is degenerate, or the
/// microfacet would face away from either direction.
struct MicrofacetPair {
    Vec3 wm;
    double etap = 1;
    bool reflect = false;
};
inline std::optional<MicrofacetPair> microfacet_pair(const Vec3& wo, const Vec3& wi, double eta) {
    const double co = wo.z, ci = wi.z;
    if (co == 0 || ci == 0) return std::nullopt;
    MicrofacetPair p;
    p.reflect = co * ci > 0;
    p.etap = p.reflect ? 1.0 : (co > 0 ? eta : 1.0 / eta);
    Vec3 wm = wi * p.etap + wo;
    if (!(dot(wm, wm) > 0)) return std::nullopt;
    wm = normalize(wm);
    if (wm.z < 0) wm = -wm;
    if (dot(wm, wi) * ci < 0 || dot(wm, wo) * co < 0) return std::nullopt;  // back-facing
    p.wm = wm;
    return p;
}

/// f(wo, wi) of the rough dielectric (alpha > 0) [Walter et al. 2007, Eqs. 20 and 21].
inline double rough_dielectric_f(const Vec3& wo, const Vec3& wi, double eta, double alpha,
                                 TransportMode mode) {
    const auto mp = microfacet_pair(wo, wi, eta);
    if (!mp) return 0;
    const Vec3& wm = mp->wm;
    const double F = fresnel_signed(dot(wo, wm), eta);
    if (mp->reflect)
        return ggx::D(wm, alpha) * ggx::G(wo, wi, alpha) * F / std::abs(4 * wi.z * wo.z);
    const double d = dot(wi, wm) + dot(wo, wm) / mp->etap;
    const double denom = d * d * wi.z * wo.z;
    double ft = ggx::D(wm, alpha) * (1 - F) * ggx::G(wo, wi, alpha) *
                std::abs(dot(wi, wm) * dot(wo, wm) / denom);
    if (mode == TransportMode::kRadiance) ft /= mp->etap * mp->etap;
    return ft;
}

}  // namespace ssslab::dielectric
