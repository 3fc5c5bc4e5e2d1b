#include "core/light.h"

#include "core/config.h"
#include "core/format.h"
#include "core/hash.h"
#include "core/warp.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace ssslab {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Direction at cosine c to axis and azimuth 2 pi v (the real-time renderer's stratification).
Vec3 around(const Vec3& axis, double c, double v) {
    Vec3 s, t;
    basis(axis, s, t);
    const double sn = std::sqrt(std::max(0.0, 1 - c * c)), phi = 2 * kPi * v;
    return normalize(s * (sn * std::cos(phi)) + t * (sn * std::sin(phi)) + axis * c);
}

// A uniform point of the disc of radius r about c facing the unit direction d (Frame(d)).
Vec3 disc_point(const Vec3& c, const Vec3& d, double r, double u1, double u2) {
    const double rr = r * std::sqrt(u1), phi = 2 * kPi * u2;
    return c + Frame(d).world({rr * std::cos(phi), rr * std::sin(phi), 0});
}

}  // namespace

const char* to_string(LightType t) {
    return name_of(t).data();
}

std::string light_type_names() {
    return names_joined<LightType>();
}

LightType parse_light_type(std::string_view name) {
    if (const auto t = parse_name<LightType>(name)) return *t;
    throw std::invalid_argument("unknown light type \"" + std::string(name) + "\" (one of " +
                                light_type_names() + ")");
}

SceneLight read_light(ConfigTable& t) {
    SceneLight l;
    l.where = t.location("type");
    if (!t.has("type")) t.fail("type", "required: one of " + light_type_names());
    l.type = parse_light_type(t.choice("type", "", names_of<LightType>()));
    switch (l.type) {
        case LightType::kDirectional: {
            const Vec3 d = t.vec3("direction");
            if (!(length(d) > 0)) t.fail("direction", "the direction towards the light is zero");
            l.direction = normalize(d);
            l.color = t.rgb("irradiance", Range::nonnegative());
            l.angular_radius_deg = t.number("angular_radius_deg", 0.0, Range::right_open(0, 90));
            break;
        }
        case LightType::kPoint:
            l.position = t.vec3("position");
            l.color = t.rgb("intensity", Range::nonnegative());
            break;
        case LightType::kSphere:
            l.position = t.vec3("position");
            l.radius = t.number("radius", Range::positive());
            l.color = t.rgb("radiance", Range::nonnegative());
            break;
        case LightType::kEnvironment:
            l.color = t.rgb("radiance", Range::nonnegative());
            break;
        case LightType::kSpot: {
            l.position = t.vec3("position");
            const Vec3 d = t.vec3("direction");
            if (!(length(d) > 0)) t.fail("direction", "the direction the spot points in is zero");
            l.direction = normalize(d);
            l.color = t.rgb("intensity", Range::nonnegative());
            l.outer_cone_deg = t.number("outer_cone_angle_deg", 45.0, Range::left_open(0, 90));
            l.inner_cone_deg =
                t.number("inner_cone_angle_deg", 0.0, Range::right_open(0, l.outer_cone_deg));
            break;
        }
    }
    return l;
}

void add_to_key(ContentKey& k, const std::string& p, const SceneLight& l) {
    k.add(p + "type", to_string(l.type)).add(p + "color", l.color);
    k.add(p + "direction", l.direction);
    k.add(p + "angular_radius_deg", l.angular_radius_deg);
    k.add(p + "position", l.position);
    k.add(p + "radius", l.radius);
    if (l.type == LightType::kSpot)  // (only here: the other types' keys stay as they were)
        k.add(p + "inner_cone_deg", l.inner_cone_deg).add(p + "outer_cone_deg", l.outer_cone_deg);
}

std::string describe(const SceneLight& l) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s (%g, %g, %g)", to_string(l.type), l.color[0], l.color[1],
                  l.color[2]);
    return buf;
}

std::string json_members(const SceneLight& l) {
    auto vec = [](const Vec3& v) {
        return "[" + format_g(v.x, 17) + ", " + format_g(v.y, 17) + ", " + format_g(v.z, 17) + "]";
    };
    auto rgb = [](const std::array<double, 3>& v) {
        return "[" + format_g(v[0], 17) + ", " + format_g(v[1], 17) + ", " + format_g(v[2], 17) +
               "]";
    };
    switch (l.type) {
        case LightType::kDirectional:
            return ", \"direction\": " + vec(l.direction) + ", \"irradiance\": " + rgb(l.color) +
                   ", \"angular_radius_deg\": " + format_g(l.angular_radius_deg, 17);
        case LightType::kPoint:
            return ", \"position\": " + vec(l.position) + ", \"intensity\": " + rgb(l.color);
        case LightType::kSphere:
            return ", \"position\": " + vec(l.position) +
                   ", \"radius\": " + format_g(l.radius, 17) + ", \"radiance\": " + rgb(l.color);
        case LightType::kEnvironment:
            return ", \"radiance\": " + rgb(l.color);
        case LightType::kSpot:
            return ", \"position\": " + vec(l.position) + ", \"direction\": " + vec(l.direction) +
                   ", \"intensity\": " + rgb(l.color) +
                   ", \"inner_cone_angle_deg\": " + format_g(l.inner_cone_deg, 17) +
                   ", \"outer_cone_angle_deg\": " + format_g(l.outer_cone_deg, 17);
    }
    return "";
}

bool delta_equivalent(const SceneLight& l, SceneLight& d) {
    d = l;
    switch (l.type) {
        case LightType::kDirectional:
            d.angular_radius_deg = 0;
            return true;
        case LightType::kPoint:
        case LightType::kSpot:
            return true;
        case LightType::kSphere:
            d.type = LightType::kPoint;
            for (double& c : d.color) c *= std::numbers::pi * l.radius * l.radius;
            d.radius = 0;
            return true;
        case LightType::kEnvironment:
            return false;
    }
    return false;
}

Light::Light(const SceneLight& sl)
    : type(sl.type),
      L(sl.color),
      color(sl.color),
      dir(sl.direction),
      pos(sl.position),
      radius(sl.radius) {
    if (sl.type == LightType::kDirectional && sl.angular_radius_deg > 0 && sl.disc_cos_max() < 1) {
        cos_max = sl.disc_cos_max();
        disc_psa = sl.disc_projected_solid_angle();
        for (double& x : L) x /= disc_psa;
    }
    if (sl.type == LightType::kSpot) {
        // [KHR_lights_punctual, "Inner and Outer Cone Angles"]
        const double ci = std::cos(sl.inner_cone_deg * kPi / 180);
        cos_outer = std::cos(sl.outer_cone_deg * kPi / 180);
        spot_scale = 1 / std::max(0.001, ci - cos_outer);
        spot_offset = -cos_outer * spot_scale;
    }
}

bool Light::is_delta() const {
    return type == LightType::kPoint || type == LightType::kSpot ||
           (type == LightType::kDirectional && cos_max == 1);
}
bool Light::is_distant() const {
    return type == LightType::kDirectional || type == LightType::kEnvironment;
}
bool Light::has_surface() const {
    return type == LightType::kSphere;
}
bool Light::subtends_cone() const {
    return type == LightType::kSphere || (type == LightType::kDirectional && cos_max < 1);
}

double Light::hit(const Vec3& o, const Vec3& d) const {
    return type == LightType::kSphere ? ray_sphere_hit(o, d, pos, radius) : kInf;
}

bool Light::seen_escaping(const Vec3& d) const {
    return type == LightType::kEnvironment ||
           (type == LightType::kDirectional && cos_max < 1 && dot(d, dir) >= cos_max);
}

bool Light::escape_cone(Vec3& axis, double& cos_half_angle) const {
    if (type == LightType::kEnvironment) {
        axis = {0, 0, 1};
        cos_half_angle = -1;
        return true;
    }
    if (type == LightType::kDirectional && cos_max < 1) {
        axis = dir;
        cos_half_angle = cos_max;
        return true;
    }
    return false;
}

const Light* nearest_light_surface(const std::vector<Light>& lights, const Vec3& o, const Vec3& d,
                                   double& t) {
    const Light* hit = nullptr;
    t = kInf;
    for (const Light& l : lights)
        if (l.has_surface()) {
            const double tl = l.hit(o, d);
            if (tl < t) t = tl, hit = &l;
        }
    return hit;
}

std::array<double, 3> escaped_radiance(const std::vector<Light>& lights, const Vec3& d) {
    std::array<double, 3> L{};
    for (const Light& l : lights)
        if (l.seen_escaping(d))
            for (std::size_t c = 0; c < 3; ++c) L[c] += l.L[c];
    return L;
}

bool Light::cone(const Vec3& x, Vec3& to, double& angle) const {
    if (type == LightType::kSphere) {
        const Vec3 v = pos - x;
        const double dist = length(v);
        if (!(dist > radius)) return false;
        to = v * (1 / dist);
        angle = std::asin(radius / dist);
    } else {
        to = dir;
        angle = std::acos(cos_max);
    }
    return true;
}

LightSample Light::sample(const Vec3& p, double u1, double u2, const Vec3* n) const {
    LightSample s;
    switch (type) {
        case LightType::kSphere: {
            const Vec3 pc = pos - p;
            const double d2 = dot(pc, pc);
            if (d2 <= radius * radius) return s;
            const double cm = std::sqrt(std::max(0.0, 1 - radius * radius / d2));
            s.wi = sample_cone(normalize(pc), cm, u1, u2);
            s.dist = ray_sphere_hit(p, s.wi, pos, radius);
            if (!std::isfinite(s.dist)) s.dist = std::sqrt(d2);  // grazing: rounding
            s.value = L;
            s.pdf = 1 / (2 * kPi * (1 - cm));
            s.ok = cm < 1;
            return s;
        }
        case LightType::kEnvironment: {
            s.value = L;
            if (n) {
                const Vec3 w = sample_cosine_hemisphere(u1, u2);
                s.wi = Frame(*n).world(w);
                s.pdf = w.z / kPi;
                s.ok = w.z > 0;
                return s;
            }
            s.wi = sample_sphere(u1, u2);
            s.pdf = 1 / (4 * kPi);
            s.ok = true;
            return s;
        }
        case LightType::kDirectional:
            if (cos_max < 1) {
                s.wi = sample_cone(dir, cos_max, u1, u2);
                s.pdf = 1 / (2 * kPi * (1 - cos_max));
            } else {
                s.wi = dir;
            }
            s.value = L;
            s.ok = true;
            return s;
        case LightType::kPoint:
        case LightType::kSpot: {
            const Vec3 pp = pos - p;
            s.dist = length(pp);
            if (!(s.dist > 0)) return s;
            s.wi = pp * (1 / s.dist);
            const double f = spot_factor(-dot(s.wi, dir));
            for (std::size_t c = 0; c < 3; ++c) s.value[c] = L[c] * f / (s.dist * s.dist);
            s.ok = f > 0;
            return s;
        }
    }
    return s;
}

double Light::pdf(const Vec3& p, const Vec3& wi, const Vec3* n) const {
    switch (type) {
        case LightType::kSphere: {
            const Vec3 pc = pos - p;
            const double d2 = dot(pc, pc);
            if (d2 <= radius * radius) return 0;
            const double cm = std::sqrt(std::max(0.0, 1 - radius * radius / d2));
            if (dot(wi, normalize(pc)) < cm) return 0;
            return 1 / (2 * kPi * (1 - cm));
        }
        case LightType::kEnvironment:
            return n ? std::max(0.0, dot(wi, *n)) / kPi : 1 / (4 * kPi);
        case LightType::kDirectional:
            if (cos_max < 1 && dot(wi, dir) >= cos_max) return 1 / (2 * kPi * (1 - cos_max));
            return 0;
        case LightType::kPoint:
        case LightType::kSpot:
            return 0;
    }
    return 0;
}

double fibonacci_u(int i, int n) {
    return (i + 0.5) / n;
}
double fibonacci_v(int i) {
    const double g = 0.5 * (std::sqrt(5.0) - 1);  // 1 / golden ratio
    const double x = i * g;
    return x - std::floor(x);
}

std::vector<LightEmitter> Light::stratify(int n, int n_environment, const Vec3& lo,
                                          const Vec3& hi) const {
    std::vector<LightEmitter> out;
    switch (type) {
        case LightType::kDirectional: {
            const Vec3 axis = normalize(dir);
            if (cos_max == 1) {
                LightEmitter e;
                e.w = axis;
                e.value = color;
                out.push_back(e);
                break;
            }
            const double L_per = 1.0 / disc_psa;
            const double omega = 2 * kPi * (1 - cos_max);
            for (int k = 0; k < n; ++k) {
                LightEmitter e;
                // Uniform in solid angle over the cone: cos theta uniform in [cos_max, 1].
                e.w = around(axis, 1 - fibonacci_u(k, n) * (1 - cos_max), fibonacci_v(k));
                for (std::size_t c = 0; c < 3; ++c) e.value[c] = color[c] * L_per * omega / n;
                out.push_back(e);
            }
            break;
        }
        case LightType::kPoint:
        case LightType::kSpot: {
            LightEmitter e;
            e.directional = false;
            e.pos = pos;
            e.value = color;
            if (type == LightType::kSpot) {  // towards w_i: cos theta = -dir . w_i
                e.lobe = true;
                e.lobe_n = dir;
                e.lobe_scale = spot_scale;
                e.lobe_offset = spot_offset;
                e.lobe_squared = true;
            }
            out.push_back(e);
            break;
        }
        case LightType::kSphere: {
            if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) break;
            // The cap every point of the box could see: around the axis towards the box,
            // half-angle (largest angle of a box corner off the axis) + arccos(r / (largest
            // corner distance)), the visible cap of the farthest point.
            const Vec3 c0 = pos;
            const Vec3 centre = (lo + hi) * 0.5;
            const Vec3 axis = length(centre - c0) > 0 ? normalize(centre - c0) : Vec3{0, 0, 1};
            double ang = 0, dmax = 0;
            for (int k = 0; k < 8; ++k) {
                const Vec3 corner{k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z};
                const Vec3 d = corner - c0;
                const double len = length(d);
                dmax = std::max(dmax, len);
                if (len > 0)
                    ang = std::max(ang, std::acos(std::clamp(dot(d, axis) / len, -1.0, 1.0)));
            }
            const double rim = std::acos(std::clamp(radius / std::max(dmax, 1e-300), 0.0, 1.0));
            const double cap = std::min(kPi, ang + rim), cos_cap = std::cos(cap);
            const double area = 2 * kPi * radius * radius * (1 - cos_cap);
            for (int k = 0; k < n; ++k) {
                LightEmitter e;
                e.directional = false;
                e.lobe = true;
                e.lobe_n = around(axis, 1 - fibonacci_u(k, n) * (1 - cos_cap), fibonacci_v(k));
                e.pos = c0 + e.lobe_n * radius;
                // A patch of area A / n with radiance L: intensity L (A / n) cos towards w.
                for (std::size_t c = 0; c < 3; ++c) e.value[c] = color[c] * area / n;
                out.push_back(e);
            }
            break;
        }
        case LightType::kEnvironment: {
            const int m = n_environment;
            for (int k = 0; k < m; ++k) {
                LightEmitter e;
                const double z = 1 - 2 * fibonacci_u(k, m),
                             rr = std::sqrt(std::max(0.0, 1 - z * z));
                const double phi = 2 * kPi * fibonacci_v(k);
                e.w = {rr * std::cos(phi), rr * std::sin(phi), z};
                for (std::size_t c = 0; c < 3; ++c) e.value[c] = color[c] * 4 * kPi / m;
                e.environment = true;
                out.push_back(e);
            }
            break;
        }
    }
    return out;
}

bool Light::centre(LightEmitter& e) const {
    e = LightEmitter{};
    switch (type) {
        case LightType::kDirectional:
            e.w = normalize(dir);
            return true;
        case LightType::kPoint:
        case LightType::kSphere:
        case LightType::kSpot:
            e.directional = false;
            e.pos = pos;
            return true;
        case LightType::kEnvironment:
            return false;
    }
    return false;
}

EmittedRay Light::sample_emission(double u1, double u2, double u3, double u4,
                                  const Vec3& scene_centre, double scene_radius) const {
    EmittedRay r;
    switch (type) {
        case LightType::kSphere: {
            const Vec3 n = sample_sphere(u1, u2);
            const Vec3 w = sample_cosine_hemisphere(u3, u4);
            r.o = pos + n * radius;
            r.d = Frame(n).world(w);
            r.value = L;
            r.pdf_pos = 1 / (4 * kPi * radius * radius);
            r.pdf_dir = w.z / kPi;
            r.ok = w.z > 0;
            // L cos / (pdf_pos cos / pi) = L pi 4 pi r^2: the sphere's power per unit radiance.
            for (std::size_t c = 0; c < 3; ++c) r.weight[c] = L[c] * kPi / r.pdf_pos;
            return r;
        }
        case LightType::kPoint:
            r.o = pos;
            r.d = sample_sphere(u3, u4);
            r.value = L;
            r.pdf_pos = 1;
            r.delta_pos = true;
            r.pdf_dir = 1 / (4 * kPi);
            r.ok = true;
            for (std::size_t c = 0; c < 3; ++c) r.weight[c] = L[c] * 4 * kPi;
            return r;
        case LightType::kSpot: {
            // Uniform in the outer cone, weighted by the falloff.
            r.o = pos;
            r.d = sample_cone(dir, cos_outer, u3, u4);
            r.pdf_pos = 1;
            r.delta_pos = true;
            r.pdf_dir = 1 / (2 * kPi * (1 - cos_outer));
            const double f = spot_factor(dot(r.d, dir));
            for (std::size_t c = 0; c < 3; ++c) {
                r.value[c] = L[c] * f;
                r.weight[c] = r.value[c] / r.pdf_dir;
            }
            r.ok = f > 0;
            return r;
        }
        case LightType::kDirectional:
        case LightType::kEnvironment: {
            if (!(scene_radius > 0)) return r;
            if (type == LightType::kEnvironment) {
                r.d = sample_sphere(u3, u4);
                r.pdf_dir = 1 / (4 * kPi);
            } else if (cos_max < 1) {
                r.d = -sample_cone(dir, cos_max, u3, u4);
                r.pdf_dir = 1 / (2 * kPi * (1 - cos_max));
            } else {
                r.d = -dir;
                r.pdf_dir = 1;
                r.delta_dir = true;
            }
            // The disc facing the ray, one scene radius upstream of the centre: every ray in
            // direction d that crosses the scene's bounding sphere crosses it.
            r.o = disc_point(scene_centre - r.d * scene_radius, r.d, scene_radius, u1, u2);
            r.pdf_pos = 1 / (kPi * scene_radius * scene_radius);
            r.value = L;
            r.ok = true;
            for (std::size_t c = 0; c < 3; ++c) r.weight[c] = L[c] / (r.pdf_pos * r.pdf_dir);
            return r;
        }
    }
    return r;
}

}  // namespace ssslab
