#include "volpath/lights.h"

#include "volpath/sampling.h"

#include <algorithm>
#include <cmath>

namespace ssslab::volpath {

Light make_light(const SceneLight& sl) {
    Light l;
    l.type = sl.type;
    l.L = sl.color;
    l.dir = sl.direction;
    l.pos = sl.position;
    l.radius = sl.radius;
    if (sl.type == LightType::kDirectional && sl.angular_radius_deg > 0) {
        l.cos_max = sl.disc_cos_max();
        for (double& x : l.L) x /= sl.disc_projected_solid_angle();
    }
    return l;
}

Vec3 sample_cone(const Vec3& axis, double cos_max, double u1, double u2) {
    const double c = 1 - u1 * (1 - cos_max), sn = std::sqrt(std::max(0.0, 1 - c * c));
    const double phi = 2 * kPi * u2;
    return Frame(axis).world({sn * std::cos(phi), sn * std::sin(phi), c});
}

LightSample sample_light(const Light& l, const Vec3& p, double u1, double u2, const Vec3* n) {
    LightSample s;
    switch (l.type) {
        case LightType::kSphere: {
            const Vec3 pc = l.pos - p;
            const double d2 = dot(pc, pc);
            if (d2 <= l.radius * l.radius) return s;
            const double cos_max = std::sqrt(std::max(0.0, 1 - l.radius * l.radius / d2));
            s.wi = sample_cone(normalize(pc), cos_max, u1, u2);
            s.dist = ray_sphere_hit(p, s.wi, l.pos, l.radius);
            if (!std::isfinite(s.dist)) s.dist = std::sqrt(d2);  // grazing: rounding
            s.value = l.L;
            s.pdf = 1 / (2 * kPi * (1 - cos_max));
            s.ok = cos_max < 1;
            return s;
        }
        case LightType::kEnvironment: {
            s.value = l.L;
            if (n) {
                const Vec3 w = sample_cosine_hemisphere(u1, u2);
                s.wi = Frame(*n).world(w);
                s.pdf = w.z / kPi;
                s.ok = w.z > 0;
                return s;
            }
            const double z = 1 - 2 * u1, r = std::sqrt(std::max(0.0, 1 - z * z)),
                         phi = 2 * kPi * u2;
            s.wi = {r * std::cos(phi), r * std::sin(phi), z};
            s.pdf = 1 / (4 * kPi);
            s.ok = true;
            return s;
        }
        case LightType::kDirectional:
            if (l.cos_max < 1) {
                s.wi = sample_cone(l.dir, l.cos_max, u1, u2);
                s.pdf = 1 / (2 * kPi * (1 - l.cos_max));
            } else {
                s.wi = l.dir;
            }
            s.value = l.L;
            s.ok = true;
            return s;
        case LightType::kPoint: {
            const Vec3 pp = l.pos - p;
            s.dist = length(pp);
            if (!(s.dist > 0)) return s;
            s.wi = pp * (1 / s.dist);
            for (int c = 0; c < 3; ++c)
                s.value[static_cast<size_t>(c)] = l.L[static_cast<size_t>(c)] / (s.dist * s.dist);
            s.ok = true;
            return s;
        }
    }
    return s;
}

double light_pdf(const Light& l, const Vec3& p, const Vec3& wi, const Vec3* n) {
    switch (l.type) {
        case LightType::kSphere: {
            const Vec3 pc = l.pos - p;
            const double d2 = dot(pc, pc);
            if (d2 <= l.radius * l.radius) return 0;
            const double cos_max = std::sqrt(std::max(0.0, 1 - l.radius * l.radius / d2));
            if (dot(wi, normalize(pc)) < cos_max) return 0;
            return 1 / (2 * kPi * (1 - cos_max));
        }
        case LightType::kEnvironment:
            return n ? std::max(0.0, dot(wi, *n)) / kPi : 1 / (4 * kPi);
        case LightType::kDirectional:
            if (l.cos_max < 1 && dot(wi, l.dir) >= l.cos_max)
                return 1 / (2 * kPi * (1 - l.cos_max));
            return 0;
        case LightType::kPoint:
            return 0;
    }
    return 0;
}

}  // namespace ssslab::volpath
