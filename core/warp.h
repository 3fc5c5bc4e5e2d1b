// Warps of uniform numbers onto directions, shared by every engine that samples a light (the light
// model, core/light.h) and by the path tracer's own sampling (volpath/sampling.h uses these).
#pragma once

#include "core/vec3.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ssslab {

/// An orthonormal frame about a unit normal n (basis above): local (x, y, z) with z along n, and
/// back.
struct Frame {
    Vec3 s, t, n;
    explicit Frame(const Vec3& normal) : n(normal) { basis(n, s, t); }
    Vec3 local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3 world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

/// A direction on the hemisphere of +z with density cos(theta) / pi (Malley's method: a uniform
/// point on the unit disc lifted onto the hemisphere), for uniform u1, u2.
inline Vec3 sample_cosine_hemisphere(double u1, double u2) {
    const double r = std::sqrt(u1), phi = 2 * std::numbers::pi * u2;
    return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1 - u1))};
}

/// A direction uniform in the cone of directions within acos(cos_max) of the unit `axis`
/// (density 1 / (2 pi (1 - cos_max))).
inline Vec3 sample_cone(const Vec3& axis, double cos_max, double u1, double u2) {
    const double c = 1 - u1 * (1 - cos_max), sn = std::sqrt(std::max(0.0, 1 - c * c));
    const double phi = 2 * std::numbers::pi * u2;
    return Frame(axis).world({sn * std::cos(phi), sn * std::sin(phi), c});
}

/// A direction uniform on the unit sphere (density 1 / (4 pi)).
inline Vec3 sample_sphere(double u1, double u2) {
    const double z = 1 - 2 * u1, r = std::sqrt(std::max(0.0, 1 - z * z)),
                 phi = 2 * std::numbers::pi * u2;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

}  // namespace ssslab
