// The renderer's lights (volpath/render.cpp): a scene light as the path tracer sees it, sampling
// a direction towards it from a point (the next-event estimation of every vertex) and the
// solid-angle density of that sampling (for MIS with BSDF and phase sampling). Where a ray meets
// a sphere light: core/vec3.h ray_sphere_hit. Spherical area lights (the cone they subtend,
// uniformly), the constant environment (uniform directions), directional lights (a disc of finite
// angular radius, or a delta) and point lights. tests/test_lights.cpp holds the sampling to its
// density by a chi-square test and the estimates to closed-form irradiance.
#pragma once

#include "core/scene.h"
#include "core/vec3.h"

#include <array>
#include <limits>

namespace ssslab::volpath {

struct Light {
    LightType type = LightType::kEnvironment;
    /// Radiance (sphere, environment, disc), irradiance (delta directional) or intensity (point).
    std::array<double, 3> L{};
    Vec3 dir, pos;
    double radius = 0;
    double cos_max = 1;  ///< disc: cosine of the angular radius
};

/// The light of a scene light: a directional light of angular radius a becomes a disc of
/// radiance E / (pi sin^2 a), so that a surface facing it receives the irradiance E.
Light make_light(const SceneLight& sl);

struct LightSample {
    Vec3 wi;
    double dist = std::numeric_limits<double>::infinity();
    /// Radiance, or for delta lights the irradiance at p (normal incidence).
    std::array<double, 3> value{};
    double pdf = 0;  ///< solid angle (0: delta)
    bool ok = false;
};

/// A direction towards light `l` from p for uniform u1, u2. `n`: the unit normal of a surface
/// at p whose outer hemisphere alone receives light (null inside a medium): the environment is
/// then sampled in proportion to cos(theta) about n, which a diffuse surface under a constant
/// sky integrates without noise (the uniform sphere wasted half of its samples below the
/// surface and weighted the rest by 4 pi cos(theta)); other lights ignore n.
LightSample sample_light(const Light& l, const Vec3& p, double u1, double u2,
                         const Vec3* n = nullptr);

/// Solid-angle density with which sample_light picks direction wi from p (0 for delta lights
/// and directions it never picks), for the same n.
double light_pdf(const Light& l, const Vec3& p, const Vec3& wi, const Vec3* n = nullptr);

/// A direction uniform in the cone of directions within acos(cos_max) of the unit `axis`.
Vec3 sample_cone(const Vec3& axis, double cos_max, double u1, double u2);

}  // namespace ssslab::volpath
