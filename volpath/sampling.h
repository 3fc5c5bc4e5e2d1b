// The volumetric path tracer's own sampling and optics: vectors, Henyey-Greenstein phase
// function, refraction (the Fresnel reflectance is core/dielectric.h's and the orthonormal basis
// core/vec3.h's, shared with realtime/). Written independently of mcml/transport.h
// (docs/architecture.md: the two engines are independent witnesses), with different formulas where
// a choice exists (HG inversion, direction frames).
#pragma once

#include "core/dielectric.h"
#include "core/vec3.h"
#include "core/warp.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ssslab::volpath {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kInv4Pi = 0.25 / std::numbers::pi;

using ssslab::basis;  // core/vec3.h, shared with realtime/

// The frame about a normal and the cosine-weighted hemisphere: core/warp.h, shared with the light
// model (core/light.h).
using ssslab::Frame;
using ssslab::sample_cone;
using ssslab::sample_cosine_hemisphere;

/// The direction with cosine `mu` to `w` and azimuth `phi` about it (w a unit vector).
inline Vec3 rotate(const Vec3& w, double mu, double phi) {
    Vec3 s, t;
    basis(w, s, t);
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - mu * mu));
    return normalize(s * (sin_theta * std::cos(phi)) + t * (sin_theta * std::sin(phi)) + w * mu);
}

/// Henyey-Greenstein phase function per steradian, mu = cosine between the propagation
/// directions before and after scattering: (1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^(3/2)).
inline double hg_pdf(double g, double mu) {
    const double d = 1.0 + g * g - 2.0 * g * mu;
    return kInv4Pi * (1.0 - g * g) / (d * std::sqrt(d));
}

/// The cosine mu distributed by HG for uniform xi in (0, 1). The inverse CDF
/// mu = (1 + g^2 - ((1 - g^2) / (1 + g u))^2) / (2 g), u = 2 xi - 1, written without the division
/// by g: multiplying out gives the polynomial form
///     mu = (u + g (u^2 + 3) / 2 + g^2 u + g^3 (u^2 - 1) / 2) / (1 + g u)^2,
/// exact for every g in (-1, 1) including g = 0 (mu = u), so no small-|g| branch is needed.
inline double sample_hg(double g, double xi) {
    const double u = 2.0 * xi - 1.0;
    const double d = 1.0 + g * u;
    const double num = u + g * (0.5 * (u * u + 3.0) + g * (u + 0.5 * g * (u * u - 1.0)));
    return std::clamp(num / (d * d), -1.0, 1.0);
}

/// The von Mises-Fisher density per steradian about the unit axis mu with concentration
/// kappa > 0: kappa exp(kappa (cos - 1)) / (2 pi (1 - exp(-2 kappa))), cos = dot(w, mu).
inline double vmf_pdf(const Vec3& mu, double kappa, const Vec3& w) {
    return kappa * std::exp(kappa * (dot(w, mu) - 1.0)) / (2.0 * kPi * -std::expm1(-2.0 * kappa));
}

/// A direction with density vmf_pdf(mu, kappa, .) for uniform u1, u2: the cosine by the inverse
/// of its distribution, cos = 1 + ln(u1 + (1 - u1) exp(-2 kappa)) / kappa, the azimuth 2 pi u2.
inline Vec3 sample_vmf(const Vec3& mu, double kappa, double u1, double u2) {
    const double c =
        std::clamp(1.0 + std::log(u1 + (1.0 - u1) * std::exp(-2.0 * kappa)) / kappa, -1.0, 1.0);
    return rotate(mu, c, 2.0 * kPi * u2);
}

/// Exact dielectric Fresnel reflectance: one copy for both renderers (core/dielectric.h).
using dielectric::fresnel_dielectric;

/// Direction refracted through an interface with unit normal n on the incident side
/// (dot(d, n) < 0), for the cosine cos_t from fresnel_dielectric and eta = n_t / n_i.
inline Vec3 refract(const Vec3& d, const Vec3& n, double eta, double cos_t) {
    const double cos_i = -dot(d, n);
    return normalize(d * (1.0 / eta) + n * (cos_i / eta - cos_t));
}

/// Snell's law in tangential form, for where no Fresnel cosine is at hand (the guides' aims):
/// the unit direction d crossing an interface with unit normal n of either orientation (d goes on
/// to the side of sign(dot(d, n)) n), ratio = n_i / n_t. The refracted direction (unit up to
/// rounding) in `out`, or false at total internal reflection.
inline bool snell(const Vec3& d, const Vec3& n, double ratio, Vec3& out) {
    const double c = dot(d, n);
    const Vec3 t = (d - n * c) * ratio;
    const double s2 = dot(t, t);
    if (!(s2 < 1)) return false;
    const double r = std::sqrt(1 - s2);
    out = c > 0 ? t + n * r : t - n * r;
    return true;
}

/// Mirror reflection of d about the plane with normal n.
inline Vec3 reflect(const Vec3& d, const Vec3& n) {
    return d - n * (2.0 * dot(d, n));
}

}  // namespace ssslab::volpath
