// The light model (core/light.h) on its own: sampled directions against the
// density Light::pdf states (chi-square over equal-solid-angle cells, Sidak over the lights),
// the estimate of irradiance sum L cos / pdf against its closed form (a sphere light or a
// disc seen from a surface facing it: L pi sin^2(alpha); the environment: L pi), sphere hits
// on the sphere, and the delta lights' values.
#include "core/light.h"
#include "core/rng.h"
#include "core/stats.h"
#include "testing.h"
#include "volpath/sampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace ssslab::volpath {
namespace {

SceneLight scene_light(LightType type) {
    SceneLight l;
    l.type = type;
    l.color = {2.0, 1.0, 0.5};
    return l;
}

// Lights seen from the origin, with the axis of their cone of directions (cos_max < 1 for the
// cones; -1 for the whole sphere).
struct Case {
    const char* name;
    Light light;
    Vec3 axis;
    double cos_max;
};

std::vector<Case> cases() {
    std::vector<Case> out;
    SceneLight s = scene_light(LightType::kSphere);
    s.position = {1, 2, 2};  // distance 3
    s.radius = 1.2;
    out.push_back({"sphere", Light(s), normalize(s.position), std::sqrt(1 - 0.16)});
    SceneLight near = s;
    near.radius = 2.99;  // nearly touching: a cone of almost a hemisphere
    out.push_back({"sphere near", Light(near), normalize(s.position),
                   std::sqrt(1 - (2.99 / 3) * (2.99 / 3))});
    SceneLight d = scene_light(LightType::kDirectional);
    d.direction = normalize(Vec3{-1, 0.5, 2});
    d.angular_radius_deg = 5;
    out.push_back({"disc", Light(d), d.direction, std::cos(5 * kPi / 180)});
    SceneLight sun = d;
    sun.angular_radius_deg = 0.27;
    out.push_back({"sun", Light(sun), d.direction, std::cos(0.27 * kPi / 180)});
    out.push_back(
        {"environment", Light(scene_light(LightType::kEnvironment)), Vec3{0, 0, 1}, -1.0});
    return out;
}

// Directions in cells of equal probability: n_u bands of a coordinate u in [0, 1] that is
// uniform under the density tested, n_phi sectors of the azimuth of the local direction l.
struct CellHistogram {
    int n_u = 20, n_phi = 20;
    std::vector<double> observed = std::vector<double>(static_cast<std::size_t>(n_u * n_phi), 0.0);
    void add(double u, const Vec3& l) {
        const int a = std::min(n_u - 1, static_cast<int>(u * n_u));
        const double phi = std::atan2(l.y, l.x) + kPi;
        const int b = std::min(n_phi - 1, static_cast<int>(phi / (2 * kPi) * n_phi));
        observed[static_cast<std::size_t>(a * n_phi + b)] += 1;
    }
    // Pearson's chi-square against equal expected counts of `n` samples in all; its p-value.
    double p(std::int64_t n, double& chi2, int& dof) const {
        const std::vector<double> expected(observed.size(), static_cast<double>(n) / (n_u * n_phi));
        chi2 = testing::chi2_statistic(observed, expected, dof);
        return chi_square_p(chi2, dof);
    }
};

TEST(Lights, SampledDirectionsFollowTheStatedDensity) {
    // Cells of equal solid angle within the cone: n_mu bands of equal width in cos(theta)
    // about the axis, n_phi sectors each; every sample must carry pdf = light_pdf = 1 / cone.
    const std::int64_t n = static_cast<std::int64_t>(2e5 * testing::test_scale());
    const std::vector<Case> all = cases();
    const double alpha = testing::sidak(0.01, static_cast<int>(all.size()));
    std::uint64_t index = 0;
    for (const Case& c : all) {
        SCOPED_TRACE(c.name);
        const Frame f(c.axis);
        const double cone = 2 * kPi * (1 - c.cos_max);
        CellHistogram cells;
        RngStream rng(3, rng_domain::kTest + 60, index++);
        int bad_pdf = 0, outside = 0;
        for (std::int64_t i = 0; i < n; ++i) {
            const LightSample s = c.light.sample({0, 0, 0}, rng.uniform(), rng.uniform());
            ASSERT_TRUE(s.ok);
            const double expect = 1 / cone;
            if (std::fabs(s.pdf - expect) > 1e-9 * expect ||
                std::fabs(c.light.pdf({0, 0, 0}, s.wi) - expect) > 1e-9 * expect)
                ++bad_pdf;
            const Vec3 l = f.local(s.wi);
            const double u = (1 - l.z) / (1 - c.cos_max);  // 0 at the axis, 1 at the rim
            if (!(u >= -1e-9 && u <= 1 + 1e-9)) {
                ++outside;
                continue;
            }
            cells.add(u, l);
        }
        EXPECT_EQ(bad_pdf, 0);
        EXPECT_EQ(outside, 0);
        double chi2 = 0;
        int dof = 0;
        const double p = cells.p(n, chi2, dof);
        EXPECT_GT(p, alpha) << "chi2 " << chi2 << " over " << dof;
        std::printf("  [measured] %s: chi2 %.1f / %d, p %.3f\n", c.name, chi2, dof, p);
        // Directions outside the cone are never picked.
        const Vec3 away = f.world({std::sqrt(1 - 0.25), 0, -0.5});
        if (c.cos_max > -0.5) {
            EXPECT_EQ(c.light.pdf({0, 0, 0}, away), 0.0);
        }
    }
}

TEST(Lights, IrradianceEstimatesMatchTheClosedForms) {
    // A surface at the origin facing the light's axis: E = int L cos(theta) dw over the cone =
    // L pi sin^2(alpha) for a cone of half-angle alpha (sphere light, disc: = the stated
    // irradiance of a directional light); the upper hemisphere of the environment: L pi.
    const std::int64_t n = static_cast<std::int64_t>(1e5 * testing::test_scale());
    std::uint64_t index = 0;
    for (const Case& c : cases()) {
        SCOPED_TRACE(c.name);
        RngStream rng(4, rng_domain::kTest + 61, index++);
        BatchAccumulator e(1);  // one sample a batch
        for (std::int64_t i = 0; i < n; ++i) {
            const LightSample s = c.light.sample({0, 0, 0}, rng.uniform(), rng.uniform());
            const double cs = std::max(0.0, dot(s.wi, c.axis));
            const double v = s.value[0] * cs / s.pdf;
            e.add_batch(&v, 1);
        }
        const double sin2 = c.cos_max > -1 ? 1 - c.cos_max * c.cos_max : 1.0;
        const double closed = c.light.L[0] * kPi * sin2;
        const double z = (e.mean(0) - closed) / e.standard_error(0);
        EXPECT_LT(std::fabs(z), 4.5) << e.mean(0) << " vs " << closed;
        if (c.light.type == LightType::kDirectional) {
            EXPECT_NEAR(closed, 2.0, 1e-12);  // the scene's irradiance, by construction
        }
    }
}

TEST(Lights, TheEnvironmentAboutASurfaceNormalIsCosineDistributed) {
    // NEE at a surface samples the environment about the lit side's normal n with density
    // cos(theta) / pi: 1 - cos^2(theta) and the azimuth are then uniform, so cells of equal
    // width in both are equally likely (chi-square); every sample carries pdf = light_pdf =
    // cos / pi and lies above the surface, and a diffuse surface's irradiance L pi comes out of
    // every single sample (L cos / pdf), which is what the choice is for.
    const Light env = Light(scene_light(LightType::kEnvironment));
    const Vec3 n = normalize(Vec3{1, -2, 0.5});
    const Frame f(n);
    const std::int64_t count = static_cast<std::int64_t>(2e5 * testing::test_scale());
    CellHistogram cells;
    RngStream rng(6, rng_domain::kTest + 63, 0);
    int bad_pdf = 0, below = 0, bad_value = 0;
    for (std::int64_t i = 0; i < count; ++i) {
        const LightSample s = env.sample({0, 0, 0}, rng.uniform(), rng.uniform(), &n);
        const Vec3 l = f.local(s.wi);
        if (!s.ok || !(l.z > 0)) {
            ++below;
            continue;
        }
        const double expect = l.z / kPi;
        if (std::fabs(s.pdf - expect) > 1e-9 * expect ||
            std::fabs(env.pdf({0, 0, 0}, s.wi, &n) - expect) > 1e-9 * expect)
            ++bad_pdf;
        if (std::fabs(s.value[0] * l.z / s.pdf - 2.0 * kPi) > 1e-9) ++bad_value;
        cells.add(1 - l.z * l.z, l);
    }
    EXPECT_EQ(below, 0);
    EXPECT_EQ(bad_pdf, 0);
    EXPECT_EQ(bad_value, 0);
    double chi2 = 0;
    int dof = 0;
    const double p = cells.p(count, chi2, dof);
    EXPECT_GT(p, 0.001) << "chi2 " << chi2 << " over " << dof;
    std::printf("  [measured] environment about a normal: chi2 %.1f / %d, p %.3f\n", chi2, dof, p);
    // Below the surface: never picked; without a normal: the whole sphere, as before.
    EXPECT_EQ(env.pdf({0, 0, 0}, -n, &n), 0.0);
    EXPECT_DOUBLE_EQ(env.pdf({0, 0, 0}, -n), 1 / (4 * kPi));
}

TEST(Lights, SphereHitsLieOnTheSphereAndDeltaLightsGiveTheirValues) {
    SceneLight s = scene_light(LightType::kSphere);
    s.position = {0, 0, 5};
    s.radius = 1;
    const Light l = Light(s);
    RngStream rng(5, rng_domain::kTest + 62, 0);
    for (int i = 0; i < 1000; ++i) {
        const LightSample x = l.sample({0.3, -0.2, 0}, rng.uniform(), rng.uniform());
        ASSERT_TRUE(std::isfinite(x.dist));
        const Vec3 q = Vec3{0.3, -0.2, 0} + x.wi * x.dist;
        EXPECT_NEAR(length(q - s.position), 1.0, 1e-9);
        EXPECT_DOUBLE_EQ(ray_sphere_hit({0.3, -0.2, 0}, x.wi, s.position, s.radius), x.dist);
    }
    // Inside the sphere light: nothing to sample.
    EXPECT_FALSE(l.sample({0, 0, 5.5}, 0.3, 0.4).ok);
    EXPECT_EQ(ray_sphere_hit({0, 0, 0}, {0, 0, -1}, s.position, s.radius),
              std::numeric_limits<double>::infinity());

    SceneLight pt = scene_light(LightType::kPoint);
    pt.position = {0, 3, 4};
    const LightSample a = Light(pt).sample({0, 0, 0}, 0.5, 0.5);
    EXPECT_TRUE(a.ok);
    EXPECT_DOUBLE_EQ(a.dist, 5.0);
    EXPECT_DOUBLE_EQ(a.value[0], 2.0 / 25);  // intensity / d^2
    EXPECT_EQ(a.pdf, 0.0);
    SceneLight dl = scene_light(LightType::kDirectional);
    dl.direction = {0, 1, 0};
    const LightSample b = Light(dl).sample({0, 0, 0}, 0.5, 0.5);
    EXPECT_EQ(b.wi.y, 1.0);
    EXPECT_EQ(b.value[1], 1.0);  // the irradiance at normal incidence
    EXPECT_EQ(b.pdf, 0.0);
    EXPECT_EQ(Light(dl).pdf({0, 0, 0}, {0, 1, 0}), 0.0);
}

// Emitted rays (Light::sample_emission, for light subpaths): the power they carry onto a disc
// receiver of radius a, sum over rays crossing it from the front of their weight, against the
// closed form. A sphere light (Lambertian, radiance L, radius r) and a point light (intensity I)
// on the axis of a disc at distance D: the solid-angle fraction of the disc seen from the centre,
// (1 - D / sqrt(D^2 + a^2)) / 2 (outside a uniform Lambertian sphere the field is that of an
// isotropic point of intensity pi r^2 L), times the power 4 pi^2 r^2 L, or 4 pi I; a sun (delta or
// a disc of irradiance E) onto a disc facing it at the scene's centre: E pi a^2; the environment
// (radiance L) onto one side of any disc at the centre: pi L pi a^2. z-scores of the estimates
// (fixed seed), Sidak over the cases; and every sphere-light ray leaves its surface outwards.
TEST(Lights, EmittedRaysCarryTheLightsPowerOntoADisc) {
    struct Emission {
        const char* name;
        SceneLight light;
        Vec3 centre, normal;  // the receiver disc
        double radius, expected;
    };
    const double a = 0.5, D = 4;
    const double factor = 0.5 * (1 - D / std::sqrt(D * D + a * a));
    std::vector<Emission> es;
    {
        SceneLight l = scene_light(LightType::kSphere);
        l.position = {0.3, -0.2, 1.0};
        l.radius = 0.7;
        es.push_back({"sphere",
                      l,
                      l.position + Vec3{0, 0, -D},
                      {0, 0, 1},
                      a,
                      4 * kPi * kPi * l.radius * l.radius * l.color[0] * factor});
        SceneLight p = scene_light(LightType::kPoint);
        p.position = l.position;
        es.push_back(
            {"point", p, p.position + Vec3{D, 0, 0}, {-1, 0, 0}, a, 4 * kPi * p.color[0] * factor});
    }
    {
        // A spot (inner 10, outer 25 degrees) onto a disc on its axis of angular radius 18
        // degrees: 2 pi I int_{cos 18}^1 f(mu) dmu, f = 1 above cos 10, ((mu - cos 25) s)^2 with
        // s = 1 / (cos 10 - cos 25) between: (1 - c_i) + s^2 ((c_i - c_o)^3 - (mu_d - c_o)^3) / 3.
        SceneLight sp = scene_light(LightType::kSpot);
        sp.position = {0.3, -0.2, 1.0};
        sp.direction = normalize(Vec3{0.2, 1, -0.4});
        sp.inner_cone_deg = 10;
        sp.outer_cone_deg = 25;
        const double ci = std::cos(10 * kPi / 180), co = std::cos(25 * kPi / 180),
                     md = std::cos(18 * kPi / 180), sc = 1 / (ci - co);
        const double integral =
            (1 - ci) + sc * sc * (std::pow(ci - co, 3) - std::pow(md - co, 3)) / 3;
        es.push_back({"spot", sp, sp.position + sp.direction * D, -sp.direction,
                      D * std::tan(18 * kPi / 180), 2 * kPi * sp.color[0] * integral});
    }
    const Vec3 axis = normalize(Vec3{-1, 0.5, 2});
    SceneLight sun = scene_light(LightType::kDirectional);
    sun.direction = axis;
    es.push_back({"delta sun", sun, {0, 0, 0}, axis, a, sun.color[0] * kPi * a * a});
    sun.angular_radius_deg = 5;
    es.push_back({"disc sun", sun, {0, 0, 0}, axis, a, sun.color[0] * kPi * a * a});
    const SceneLight env = scene_light(LightType::kEnvironment);
    es.push_back({"environment",
                  env,
                  {0, 0, 0},
                  normalize(Vec3{0.2, 1, -0.3}),
                  a,
                  kPi * env.color[0] * kPi * a * a});

    const double alpha = testing::sidak(0.01, static_cast<int>(es.size()));
    const double zmax = normal_quantile(1 - alpha / 2);
    const std::int64_t n = static_cast<std::int64_t>(4e5 * testing::test_scale());
    const Vec3 scene_centre{0.1, 0, 0};
    const double scene_radius = 2;
    std::uint64_t index = 0;
    for (const Emission& e : es) {
        SCOPED_TRACE(e.name);
        const Light l(e.light);
        // (Seed 6: with seed 5 the disc sun's estimate at the slow scale, 4e6 rays, was z 3.3,
        // a 1-in-1000 draw: 2e7 rays of the same stream give z 1.3, seeds 6 and 7 z -0.1 and 1.1,
        // and 2e7 rays of another generator z 0.05 and -0.8.)
        RngStream rng(6, rng_domain::kTest + 312, index++);
        double sum = 0, sum2 = 0;
        int outwards_failures = 0;
        for (std::int64_t i = 0; i < n; ++i) {
            const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform(),
                         u4 = rng.uniform();
            const EmittedRay r = l.sample_emission(u1, u2, u3, u4, scene_centre, scene_radius);
            if (!r.ok) continue;
            if (l.has_surface() && !(dot(r.d, r.o - l.pos) > 0)) ++outwards_failures;
            const double dn = dot(r.d, e.normal);
            if (!(dn < 0)) continue;  // only rays onto the disc's front
            const double t = dot(e.centre - r.o, e.normal) / dn;
            if (!(t > 0)) continue;
            const Vec3 x = r.o + r.d * t - e.centre;
            if (dot(x, x) > e.radius * e.radius) continue;
            sum += r.weight[0];
            sum2 += r.weight[0] * r.weight[0];
        }
        const double nn = static_cast<double>(n), mean = sum / nn;
        const double se = std::sqrt(std::max(0.0, sum2 / nn - mean * mean) / nn);
        const double z = (mean - e.expected) / se;
        std::printf("  [measured] %s: power onto the disc %.5g +- %.2g, expected %.5g, z %.2f\n",
                    e.name, mean, se, e.expected, z);
        EXPECT_LT(std::fabs(z), zmax) << mean << " +- " << se << " vs " << e.expected;
        EXPECT_EQ(outwards_failures, 0);
    }
}

// A spot light (KHR_lights_punctual) seen from points around it: a delta light (pdf 0, never
// hit), its value the intensity times the cone's falloff over the squared distance, the falloff
// written here from the extension's text: full within the inner angle, none beyond the outer
// one, between them the square of the linear ramp of the cosine; its emitter in the real-time
// renderer's stratification carries the same factor.
TEST(Lights, ASpotLightFallsOffBetweenItsConeAngles) {
    SceneLight sp = scene_light(LightType::kSpot);
    sp.position = {1, 2, 3};
    sp.direction = normalize(Vec3{0, -1, 0.3});
    sp.inner_cone_deg = 20;
    sp.outer_cone_deg = 40;
    const Light l(sp);
    EXPECT_TRUE(l.is_delta());
    EXPECT_FALSE(l.has_surface() || l.is_distant() || l.subtends_cone());
    const std::vector<LightEmitter> em = l.stratify(16, 16, {-1, -1, -1}, {1, 1, 1});
    ASSERT_EQ(em.size(), 1u);
    LightEmitter centre;
    EXPECT_TRUE(l.centre(centre));
    const double ci = std::cos(20 * kPi / 180), co = std::cos(40 * kPi / 180);
    int inside = 0, ramp = 0, outside = 0;
    for (double angle = 0; angle < 90; angle += 1.7) {
        // a point at distance 2.5 at `angle` degrees off the axis
        const Vec3 off = normalize(cross(sp.direction, Vec3{1, 0, 0}));
        const double t = angle * kPi / 180;
        const Vec3 p = sp.position + (sp.direction * std::cos(t) + off * std::sin(t)) * 2.5;
        const double c = std::cos(t);
        const double f = c >= ci ? 1.0 : (c <= co ? 0.0 : std::pow((c - co) / (ci - co), 2));
        (f == 1 ? inside : (f == 0 ? outside : ramp))++;
        const LightSample s = l.sample(p, 0.3, 0.7);
        EXPECT_EQ(s.ok, f > 0) << angle;
        EXPECT_EQ(s.pdf, 0.0);
        EXPECT_EQ(l.pdf(p, s.wi), 0.0);
        EXPECT_NEAR(s.dist, 2.5, 1e-12);
        for (std::size_t k = 0; k < 3; ++k)
            EXPECT_NEAR(s.value[k], sp.color[k] * f / 6.25, 1e-12) << angle;
        const Vec3 wi = normalize(sp.position - p);
        EXPECT_NEAR(em[0].factor(wi), f, 1e-12) << angle;
        EXPECT_TRUE(std::isinf(l.hit(p, wi)));
    }
    EXPECT_GT(inside, 5);
    EXPECT_GT(ramp, 5);
    EXPECT_GT(outside, 5);
}

// The exit guide's lobe (volpath/sampling.h, the renderer's volpath-render-8): von
// Mises-Fisher directions about an axis. Its density integrates to one over the sphere
// (Simpson's rule in theta, the lobe and the rest apart), and sampled directions fall into bands of
// theta (equal widths up to where the lobe has all but 1e-6 of its mass, then the rest) and sectors
// of azimuth as often as the density integrated over each band says (chi-square, Sidak over the
// concentrations), from nearly uniform (kappa 1e-3) to a lobe a third of a degree wide (kappa 1e5,
// the renderer's cap).
TEST(Lights, VonMisesFisherDirectionsFollowTheirDensity) {
    const Vec3 axis = normalize(Vec3{0.3, -0.5, 0.8});
    const Frame f(axis);
    const double kappas[] = {1e-3, 1.0, 30.0, 1e3, 1e5};
    const double alpha = testing::sidak(0.01, static_cast<int>(std::size(kappas)));
    const std::int64_t n = static_cast<std::int64_t>(2e5 * testing::test_scale());
    std::uint64_t index = 0;
    for (const double kappa : kappas) {
        SCOPED_TRACE(kappa);
        // The density in theta, integrated by Simpson's rule over [a, b].
        auto mass = [&](double a, double b) {
            const int m = 2000;
            const double h = (b - a) / m;
            double sum = 0;
            for (int i = 0; i <= m; ++i) {
                const double t = a + i * h;
                const double v = vmf_pdf(axis, kappa, f.world({std::sin(t), 0, std::cos(t)})) * 2 *
                                 kPi * std::sin(t);
                sum += v * (i == 0 || i == m ? 1 : (i % 2 ? 4 : 2));
            }
            return sum * h / 3;
        };
        // theta_max: where 1 - cos = 14 / kappa (mass beyond: exp(-14) ~ 1e-6), or pi.
        const double t_max = kappa * 2 > 14 ? std::acos(1 - 14 / kappa) : kPi;
        EXPECT_NEAR(mass(0, t_max) + (t_max < kPi ? mass(t_max, kPi) : 0.0), 1.0, 1e-6);
        const int bands = 16, sectors = 8;
        std::vector<double> edges(bands + 1), expected, observed(bands * sectors + 1, 0.0);
        for (int b = 0; b <= bands; ++b) edges[static_cast<std::size_t>(b)] = t_max * b / bands;
        for (int b = 0; b < bands; ++b)
            for (int k = 0; k < sectors; ++k)
                expected.push_back(static_cast<double>(n) *
                                   mass(edges[static_cast<std::size_t>(b)],
                                        edges[static_cast<std::size_t>(b) + 1]) /
                                   sectors);
        expected.push_back(static_cast<double>(n) * (1 - mass(0, t_max)));
        RngStream rng(4, rng_domain::kTest + 61, index++);
        for (std::int64_t i = 0; i < n; ++i) {
            const Vec3 l = f.local(sample_vmf(axis, kappa, rng.uniform(), rng.uniform()));
            const double t = std::acos(std::clamp(l.z, -1.0, 1.0));
            if (!(t < t_max)) {
                observed.back() += 1;
                continue;
            }
            const int b = std::min(bands - 1, static_cast<int>(t / t_max * bands));
            const double phi = std::atan2(l.y, l.x) + kPi;
            const int k = std::min(sectors - 1, static_cast<int>(phi / (2 * kPi) * sectors));
            observed[static_cast<std::size_t>(b * sectors + k)] += 1;
        }
        // The last cell (beyond theta_max) expects almost nothing: merged into the band before.
        if (expected.back() < 5) {
            observed[observed.size() - 2] += observed.back();
            expected[expected.size() - 2] += expected.back();
            observed.pop_back();
            expected.pop_back();
        }
        int dof = 0;
        const double chi2 = testing::chi2_statistic(observed, expected, dof);
        const double p = chi_square_p(chi2, dof);
        EXPECT_GT(p, alpha) << "chi2 " << chi2 << " over " << dof;
        std::printf("  [measured] kappa %g: chi2 %.1f / %d, p %.3f\n", kappa, chi2, dof, p);
    }
}

}  // namespace
}  // namespace ssslab::volpath
