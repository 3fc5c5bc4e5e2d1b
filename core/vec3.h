// A 3-vector of doubles for geometry shared between modules (scenes, meshes, the path tracer).
#pragma once

#include <cmath>
#include <limits>

namespace ssslab {

struct Vec3 {
    double x = 0, y = 0, z = 0;
    Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3& operator+=(const Vec3& o) {
        x += o.x;
        y += o.y;
        z += o.z;
        return *this;
    }
    double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    bool operator==(const Vec3&) const = default;
};
inline double dot(const Vec3& a, const Vec3& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(const Vec3& a) {
    return std::sqrt(dot(a, a));
}
inline Vec3 normalize(const Vec3& a) {
    return a * (1.0 / length(a));
}
inline bool all_finite(const Vec3& a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

/// An orthonormal basis (s, t, n) around a unit vector n, continuous except on a measure-zero
/// set (Duff et al., "Building an orthonormal basis, revisited", JCGT 2017).
inline void basis(const Vec3& n, Vec3& s, Vec3& t) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    s = {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    t = {b, sign + n.y * n.y * a, -n.y};
}

/// Nearest t > 0 where the ray o + t d (d a unit vector) meets the sphere of centre c and radius
/// r; infinity if none. The sphere lights of both renderers.
inline double ray_sphere_hit(const Vec3& o, const Vec3& d, const Vec3& c, double r) {
    const Vec3 oc = o - c;
    const double b = dot(oc, d), cc = dot(oc, oc) - r * r;
    const double disc = b * b - cc;
    if (disc < 0) return std::numeric_limits<double>::infinity();
    const double s = std::sqrt(disc);
    if (-b - s > 0) return -b - s;
    if (-b + s > 0) return -b + s;
    return std::numeric_limits<double>::infinity();
}

}  // namespace ssslab
