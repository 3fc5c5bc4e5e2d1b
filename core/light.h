// The light model: every light type of a scene, once, with what each engine asks of it. The
// path tracer's next-event estimation and MIS (volpath/render.cpp), the CPU lighting pass and the
// GL twin's light packing (realtime/lighting.cpp, realtime/gl/lighting_gl.cpp), the scene's
// description and content key (core/scene.cpp) and the Cycles exporter
// (experiments/cli/cmd_scene.cpp) read it. A new light type is a case in each switch of
// core/light.cpp plus its tests (tests/test_lights.cpp); the list of the places outside this file
// pair that still know the types is in docs/architecture.md ("Adding a light type").
//
// Types, as the scene file gives them (core/scene.h):
//   directional  a direction towards the light and the irradiance E it gives a surface facing it;
//                with angular_radius_deg a > 0 a disc of radiance E / (pi sin^2 a) (the sun),
//                otherwise a delta light;
//   point        a position and an intensity [per sr] (delta);
//   sphere       a position, a radius and a radiance (a Lambertian emitter; not in any BVH: rays
//                meet it through Light::hit);
//   environment  a constant radiance from every direction;
//   spot         a position, the direction it points in, an intensity [per sr] on that axis and
//                a cone with a smooth falloff between an inner and an outer angle, as glTF's
//                KHR_lights_punctual defines it: the intensity times
//                clamp((cos theta - cos outer) / max(0.001, cos inner - cos outer), 0, 1)^2
//                (delta).
#pragma once

#include "core/enum_names.h"
#include "core/error.h"
#include "core/vec3.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

namespace ssslab {

class ConfigTable;
class ContentKey;

enum class LightType { kDirectional, kPoint, kSphere, kEnvironment, kSpot };
template <>
struct EnumNames<LightType> {
    static constexpr std::array<std::pair<LightType, std::string_view>, 5> table = {
        {{LightType::kDirectional, "directional"},
         {LightType::kPoint, "point"},
         {LightType::kSphere, "sphere"},
         {LightType::kEnvironment, "environment"},
         {LightType::kSpot, "spot"}}};
};
/// The scene file's spelling of a type ("directional", ...), and back (std::invalid_argument
/// naming the choices for an unknown name).
const char* to_string(LightType t);
LightType parse_light_type(std::string_view name);
/// Every type's spelling, in enum order ("directional, point, sphere, environment").
std::string light_type_names();

/// A light as the scene file gives it.
struct SceneLight {
    LightType type = LightType::kDirectional;
    /// Directional: irradiance on a surface facing the light; point and spot: intensity [per sr]
    /// (spot: on its axis); sphere and environment: radiance. Linear RGB, relative units.
    std::array<double, 3> color{};
    /// Directional: unit vector towards the light; spot: unit vector it points in (its axis).
    Vec3 direction{0, 0, 1};
    double angular_radius_deg = 0;  ///< directional: 0 is a delta light
    Vec3 position{};                ///< point, sphere, spot [world units]
    double radius = 0;              ///< sphere [world units]
    /// Spot: the cone's inner angle (full intensity within) and outer angle (none beyond).
    double inner_cone_deg = 0, outer_cone_deg = 45;
    SourceLocation where;

    /// A directional light of angular radius a > 0 is a disc: cos(a), the cosine of its rim...
    double disc_cos_max() const { return std::cos(angular_radius_deg * std::numbers::pi / 180); }
    /// ... and pi sin^2(a), the cosine-weighted solid angle of the disc seen face-on: its
    /// radiance is the irradiance `color` over this (both renderers).
    double disc_projected_solid_angle() const {
        const double a = angular_radius_deg * std::numbers::pi / 180;
        return std::numbers::pi * std::sin(a) * std::sin(a);
    }
};

/// A [[lights]] table of a scene file (InputError naming the key for a bad value).
SceneLight read_light(ConfigTable& t);
/// The light's values under `prefix` ("lights[0].") in a content key.
void add_to_key(ContentKey& k, const std::string& prefix, const SceneLight& l);
/// "sphere (1, 1, 1)": the type and its colour, as `ssslab scene` lists it.
std::string describe(const SceneLight& l);
/// The light's keys of the scene file as JSON members after "type" (", \"direction\": [...],
/// ..."): what `ssslab scene --export-obj` writes into scene.json for other renderers
/// (scripts/cycles_render.py), values to 17 digits.
std::string json_members(const SceneLight& l);
/// The light as one delta light of one shadow map (the speed goal's frame of `ssslab bench
/// --realtime`): a sun its axis, a sphere light a point light of the same intensity (pi r^2 times
/// its radiance) at its centre, a point light itself; false for the environment.
bool delta_equivalent(const SceneLight& l, SceneLight& delta);

/// A direction from a point towards a light (Light::sample).
struct LightSample {
    Vec3 wi;
    double dist = std::numeric_limits<double>::infinity();
    /// Radiance, or for delta lights the irradiance at p (normal incidence).
    std::array<double, 3> value{};
    double pdf = 0;  ///< solid angle (0: delta)
    bool ok = false;
};

/// One emitter of a deterministic, stratified discretisation of a light (Light::stratify): what
/// a rasterizer draws a shadow map for.
struct LightEmitter {
    bool directional = true;
    Vec3 w{};    ///< directional: unit vector towards the light
    Vec3 pos{};  ///< otherwise its position
    /// Directional: irradiance at normal incidence; otherwise intensity [per sr].
    std::array<double, 3> value{};
    /// An angular profile: the intensity towards a receiver is value * factor(w_i), w_i the unit
    /// vector from the receiver to the emitter, factor = f or min(1, f)^2 (lobe_squared) with
    /// f = max(0, -lobe_n . w_i * lobe_scale + lobe_offset): a patch of a Lambertian area light
    /// (scale 1, offset 0), a spot light's cone (core/light.h's spot rule).
    bool lobe = false;
    Vec3 lobe_n{};
    double lobe_scale = 1, lobe_offset = 0;
    bool lobe_squared = false;
    bool environment = false;  ///< a direction of the environment

    /// The profile's factor towards w_i (1 without a lobe).
    double factor(const Vec3& wi) const {
        if (!lobe) return 1;
        const double f = std::max(0.0, -dot(lobe_n, wi) * lobe_scale + lobe_offset);
        if (!lobe_squared) return f;
        const double c = std::min(1.0, f);
        return c * c;
    }
};

/// A ray leaving a light (Light::sample_emission), for light subpaths: origin, unit direction,
/// the radiance it carries (for delta lights the intensity or irradiance in place of radiance)
/// and the densities it was drawn with. `weight` is value * |cos at the origin| / (pdf_pos *
/// pdf_dir) (for a delta position or direction that density is 1): the power the ray carries, so
/// that its mean over samples is the light's emitted power (through the bounding disc for
/// distant lights).
struct EmittedRay {
    Vec3 o, d;
    std::array<double, 3> value{}, weight{};
    double pdf_pos = 0;  ///< per unit area (1 for a delta position)
    double pdf_dir = 0;  ///< per solid angle (1 for a delta direction)
    bool delta_pos = false, delta_dir = false;
    bool ok = false;
};

/// A light resolved for rendering: what every engine asks of a scene light.
struct Light {
    LightType type = LightType::kEnvironment;
    /// Radiance (sphere, environment, disc), irradiance (delta directional) or intensity (point).
    std::array<double, 3> L{};
    std::array<double, 3> color{};  ///< SceneLight::color as given (L before the disc's rule)
    Vec3 dir, pos;
    double radius = 0;
    double cos_max = 1;   ///< disc: cosine of the angular radius (1: a delta directional light)
    double disc_psa = 0;  ///< disc: SceneLight::disc_projected_solid_angle()
    /// Spot: the cosine of the outer angle and the falloff's scale and offset (KHR_lights_punctual:
    /// factor = clamp(cos theta * spot_scale + spot_offset, 0, 1)^2).
    double cos_outer = -1, spot_scale = 0, spot_offset = 1;

    /// Spot: the falloff factor at cosine c to its axis (1 for other lights).
    double spot_factor(double c) const {
        if (type != LightType::kSpot) return 1;
        const double f = std::clamp(c * spot_scale + spot_offset, 0.0, 1.0);
        return f * f;
    }

    Light() = default;
    /// A directional light of angular radius a becomes a disc of radiance E / (pi sin^2 a), so
    /// that a surface facing it receives the irradiance E; one whose cos(a) rounds to 1 stays a
    /// delta light of irradiance E.
    explicit Light(const SceneLight& sl);

    /// Reached only by sampling it (a point, a delta directional light): no ray meets it.
    bool is_delta() const;
    /// At infinity (directional, environment): seen by rays that escape the scene.
    bool is_distant() const;
    /// A surface that rays meet (a sphere light): Light::hit.
    bool has_surface() const;
    /// Subtends a cone of directions from a point outside it (a sphere, a disc): what the
    /// path tracer's exit and boundary guides aim at (Light::cone).
    bool subtends_cone() const;

    /// Nearest t > 0 where the ray o + t d (d unit) meets the light's surface; infinity if none
    /// (always for lights without a surface).
    double hit(const Vec3& o, const Vec3& d) const;
    /// Whether a ray escaping the scene in unit direction d sees this light (environment, a disc
    /// containing d); it then carries the radiance L.
    bool seen_escaping(const Vec3& d) const;
    /// The cone of directions in which escaping rays see this light (seen_escaping): its axis
    /// and the cosine of its half-angle, -1 for the whole sphere (the environment); false for
    /// lights no escaping ray sees.
    bool escape_cone(Vec3& axis, double& cos_half_angle) const;
    /// The cone a subtends_cone() light fills from x: the unit direction to its centre (a disc:
    /// its axis) and its angular radius; false inside a sphere light.
    bool cone(const Vec3& x, Vec3& to, double& angle) const;

    /// A direction towards the light from p for uniform u1, u2. `n`: the unit normal of a surface
    /// at p whose outer hemisphere alone receives light (null inside a medium): the environment
    /// is then sampled in proportion to cos(theta) about n, which a diffuse surface under a
    /// constant sky integrates without noise; other lights ignore n.
    LightSample sample(const Vec3& p, double u1, double u2, const Vec3* n = nullptr) const;
    /// Solid-angle density with which sample() picks direction wi from p (0 for delta lights and
    /// directions it never picks), for the same n.
    double pdf(const Vec3& p, const Vec3& wi, const Vec3* n = nullptr) const;

    /// The light as n stratified emitters (Fibonacci lattice: [Swinbank and Purser 2006]),
    /// n_environment for the environment; a sphere light samples the cap of itself that points
    /// of the box [lo, hi] can see (nothing for an empty box, lo > hi). Deterministic.
    std::vector<LightEmitter> stratify(int n, int n_environment, const Vec3& lo,
                                       const Vec3& hi) const;
    /// The emitter a single view of the light is taken from (a directional light's axis, a point
    /// or sphere light's centre): what the real-time renderer's thickness map is rendered from;
    /// false for the environment.
    bool centre(LightEmitter& e) const;

    /// A ray leaving the light for uniform u1..u4: a sphere light a uniform point of its surface
    /// and a cosine-weighted direction, a point light a uniform direction, distant lights a
    /// direction (the disc's cone, or uniform for the environment) and a uniform point of the
    /// disc of radius `scene_radius` about `scene_centre` facing it, upstream of the scene.
    EmittedRay sample_emission(double u1, double u2, double u3, double u4, const Vec3& scene_centre,
                               double scene_radius) const;
};

/// The nearest light surface along o + t d (d unit), t > 0; nullptr and t = infinity if none.
const Light* nearest_light_surface(const std::vector<Light>& lights, const Vec3& o, const Vec3& d,
                                   double& t);
/// What a ray escaping the scene in unit direction d sees: the sum of the radiances of the
/// lights that seen_escaping(d), in their order.
std::array<double, 3> escaped_radiance(const std::vector<Light>& lights, const Vec3& d);

/// Fibonacci lattice point i of n: (i + 1/2) / n, and the fractional golden-ratio turn of i.
double fibonacci_u(int i, int n);
double fibonacci_v(int i);

}  // namespace ssslab
