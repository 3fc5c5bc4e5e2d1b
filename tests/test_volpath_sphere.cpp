// The lit sphere of the volumetric path tracer (volpath/sphere.h) against physics and closed
// forms: the specular reflectance of a sphere, the white furnace, the index-matched absorbing
// sphere (total, beta profile, image), the non-scattering dielectric sphere (Airy-type sum over
// internal reflections), the mirror sphere's highlight intensity, hero vs per-channel, the large
// sphere against the half-space (volpath::simulate_pencil), determinism and checkpoints, stiff
// media and bad input. Expected values come from closed forms or quadrature in this file.
#include "core/error.h"
#include "core/material.h"
#include "testing.h"
#include "volpath/pencil.h"
#include "volpath/sampling.h"
#include "volpath/sphere.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <vector>

namespace ssslab::volpath {
namespace {

std::int64_t scaled(double paths) {
    return static_cast<std::int64_t>(paths * testing::test_scale());
}

Medium medium(double mua, double mus, double g, double eta, double eta_out = 1.0) {
    Medium m;
    m.name = "test";
    for (int c = 0; c < 3; ++c) {
        m.sigma_a_per_cm[c] = mua;
        m.sigma_s_per_cm[c] = mus;
        m.g[c] = g;
    }
    m.eta = eta;
    m.eta_above = m.eta_below = eta_out;
    return m;
}

SphereScene scene(const Medium& m, double radius_cm, int bins = 36, int pixels = 16) {
    SphereScene s;
    s.medium = m;
    s.radius_cm = radius_cm;
    s.to_light = {0, 0, 1};
    s.to_camera = {0, 0, 1};
    s.width = s.height = pixels;
    s.beta_bins = bins;
    return s;
}

SphereRun run(const SphereScene& s, double photons, ChromaticMode mode = ChromaticMode::kPerChannel,
              bool image = false, int threads = 0) {
    SphereOptions o;
    o.budget.samples = scaled(photons);
    o.mode = mode;
    o.image = image;
    o.threads = threads;
    return simulate_sphere(s, o);
}

double z_score(double value, double se, double expected) {
    return (value - expected) / se;
}

void expect_within(double value, double se, double expected, double k, const char* what) {
    EXPECT_TRUE(std::isfinite(value)) << what;
    const double z = z_score(value, se, expected);
    std::printf("  [measured] %s: %.8g +- %.3g vs %.8g (z = %.2f)\n", what, value, se, expected, z);
    EXPECT_LE(std::fabs(value - expected), k * se + 1e-15)
        << what << ": " << value << " +- " << se << " vs " << expected << " (z = " << z << ")";
}

// Two-sided critical |z| for `tests` tests at family-wise alpha.
double z_crit(double alpha, int tests) {
    return testing::normal_quantile(1 - testing::sidak(alpha, tests) / 2);
}

// Composite Simpson's rule with n (even) intervals.
template <class F>
double simpson(F f, double a, double b, int n) {
    const double h = (b - a) / n;
    double s = f(a) + f(b);
    for (int i = 1; i < n; ++i) s += f(a + i * h) * (i % 2 ? 4.0 : 2.0);
    return s * h / 3.0;
}

// The fraction of a collimated beam reflected by a smooth sphere, 2 int_0^1 F(mu) mu dmu, in
// the test's own way: for eta > 1 Simpson in mu (F is smooth); for eta < 1 the total reflection
// below the critical cosine gives mu_c^2, and the rest is integrated over the cosine c of the
// refracted ray, mu^2 = 1 - eta^2 (1 - c^2), mu dmu = eta^2 c dc, where the square-root kink at
// the critical angle disappears.
double specular_by_quadrature(double eta) {
    if (eta >= 1)
        return simpson([&](double mu) { return 2 * mu * fresnel_dielectric(mu, eta); }, 0, 1,
                       200000);
    const double mu_c2 = 1 - eta * eta;
    return mu_c2 + simpson(
                       [&](double c) {
                           const double mu = std::sqrt(1 - eta * eta * (1 - c * c));
                           return 2 * eta * eta * c * fresnel_dielectric(mu, eta);
                       },
                       0, 1, 200000);
}

void expect_sane(const SphereRun& r, const char* what) {
    ASSERT_FALSE(r.interrupted) << what;
    for (int c = 0; c < 3; ++c) {
        for (size_t j = 0; j < r.exitance[c].size(); ++j) {
            ASSERT_TRUE(std::isfinite(r.exitance[c][j]) && r.exitance[c][j] >= 0) << what;
            ASSERT_TRUE(std::isfinite(r.exitance_se[c][j]) && r.exitance_se[c][j] >= 0) << what;
        }
        for (double v : {r.diffuse[c], r.specular[c], r.lost[c], r.intensity_subsurface[c],
                         r.intensity_specular[c], r.diffuse_se[c]})
            EXPECT_TRUE(std::isfinite(v) && v >= 0) << what;
    }
    if (r.image) {
        for (const ImageLayer& layer : r.image->layers())
            for (float v : layer.pixels())
                ASSERT_TRUE(std::isfinite(v) && v >= 0) << what << " layer " << layer.name();
    }
}

// ---- the specular reflectance of a sphere ----------------------------------------------------

TEST(VolpathSphereOptics, SpecularReflectanceMatchesQuadrature) {
    EXPECT_EQ(sphere_specular_reflectance(1.0), 0.0);
    for (double eta : {1.5, 1.33, 2.5, 1.01, 1 / 1.33, 0.5, 0.99}) {
        const double expected = specular_by_quadrature(eta);
        EXPECT_NEAR(sphere_specular_reflectance(eta), expected, 1e-12) << eta;
        std::printf("  [measured] eta %.4g: %.15f vs quadrature %.15f\n", eta,
                    sphere_specular_reflectance(eta), expected);
    }
    // Sanity of the test's own quadrature: for eta < 1 and eta > 1 the same number from both
    // sides of the interface is not expected, but eta -> 1 must give 0, and a perfectly
    // reflecting limit (eta -> 0: everything is totally reflected) 1.
    EXPECT_NEAR(specular_by_quadrature(1e-6), 1.0, 1e-9);
}

// ---- energy ------------------------------------------------------------------------------

TEST(VolpathSphereTransport, WhiteSphereLosesNothing) {
    // Albedo 1: every photon's weight leaves, diffusely (after entering) or specularly; with the
    // deterministic entry split and analog transport that holds photon by photon.
    struct Case {
        const char* what;
        double eta, eta_out;
    };
    for (const Case& k : {Case{"eta 1", 1.0, 1.0}, Case{"eta 1.4", 1.4, 1.0},
                          Case{"eta below ambient", 1.0, 1.3}}) {
        SCOPED_TRACE(k.what);
        const SphereRun r = run(scene(medium(0.0, 10.0, 0.5, k.eta, k.eta_out), 1.0), 2e4);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(r.diffuse[c] + r.specular[c], 1.0, 1e-12);
            EXPECT_EQ(r.lost[c], 0.0);
            EXPECT_GT(r.diffuse[c], 0.5);
        }
        std::printf("  [measured] %s: diffuse %.12f + specular %.12f - 1 = %.3g\n", k.what,
                    r.diffuse[0], r.specular[0], r.diffuse[0] + r.specular[0] - 1);
    }
    // Hero mode with chromatic coefficients: the per-photon sum varies with the MIS weights.
    Medium chroma = medium(0.0, 0.0, 0.0, 1.4);
    chroma.sigma_s_per_cm = {5.0, 20.0, 60.0};
    chroma.g = {0.0, 0.5, 0.9};
    const SphereRun h = run(scene(chroma, 1.0), 3e4, ChromaticMode::kHero);
    for (int c = 0; c < 3; ++c) {
        // The specular part is the same for all channels and is not weighted: the SE of the sum
        // is at most the sum of the SEs.
        expect_within(h.diffuse[c] + h.specular[c], h.diffuse_se[c] + h.specular_se[c], 1.0,
                      z_crit(0.01, 3), "hero white sphere: diffuse + specular");
    }
}

// ---- the index-matched, non-scattering sphere ----------------------------------------------

// Exit fraction of a uniform parallel beam through an index-matched sphere of radius R with
// absorption k: (2 / R^2) int_0^R exp(-2 k sqrt(R^2 - b^2)) b db; with x = sqrt(R^2 - b^2),
// b db = -x dx: (2 / R^2) int_0^R x exp(-2 k x) dx = [1 - (1 + 2 k R) exp(-2 k R)] / (2 k^2 R^2).
double matched_exit(double k, double R) {
    const double a = 2 * k * R;
    return (1 - (1 + a) * std::exp(-a)) / (2 * k * k * R * R);
}

TEST(VolpathSphereTransport, IndexMatchedAbsorbingSphereTotalAndProfile) {
    // Every photon crosses on a straight chord; the photon entering with n . l = mu leaves at the
    // mirror point with n . l = -mu after the chord 2 R mu. So the exit through the dark-side
    // zone mu in [m0, m1] (beta = pi - acos(mu)) is int_m0^m1 2 mu exp(-a mu) dmu, a = 2 k R,
    // = G(m1) - G(m0), G(mu) = -2 exp(-a mu) (a mu + 1) / a^2, and the lit side gets nothing.
    const double R = 2.0;
    const double ks[3] = {0.1, 0.35, 1.0};
    Medium m = medium(0.0, 0.0, 0.0, 1.0);
    m.sigma_a_per_cm = {ks[0], ks[1], ks[2]};
    const int bins = 36;
    for (ChromaticMode mode : {ChromaticMode::kPerChannel, ChromaticMode::kHero}) {
        SCOPED_TRACE(to_string(mode));
        const SphereRun r = run(scene(m, R, bins), 2e5, mode);
        const double alpha = testing::sidak(0.001, 6);
        for (int c = 0; c < 3; ++c) {
            SCOPED_TRACE(kChannelNames[c]);
            const double k = ks[c], a = 2 * k * R;
            EXPECT_EQ(r.specular[c], 0.0);
            expect_within(r.diffuse[c], r.diffuse_se[c], matched_exit(k, R), z_crit(0.001, 6),
                          "matched sphere exit");
            auto G = [a](double mu) { return -2 * std::exp(-a * mu) * (a * mu + 1) / (a * a); };
            double chi2 = 0;
            int used = 0;
            for (int j = 0; j < bins; ++j) {
                const double b0 = r.beta_edge(j), b1 = r.beta_edge(j + 1);
                if (b1 <= kPi / 2 + 1e-12) {
                    EXPECT_EQ(r.exitance[c][static_cast<size_t>(j)], 0.0) << "lit bin " << j;
                    continue;
                }
                const double m0 = -std::cos(b0), m1 = -std::cos(b1);
                const double fraction = G(m1) - G(m0);
                const double expected = fraction / (2 * (std::cos(b0) - std::cos(b1)));
                const double se = r.exitance_se[c][static_cast<size_t>(j)];
                ASSERT_GT(se, 0.0) << j;
                const double z = z_score(r.exitance[c][static_cast<size_t>(j)], se, expected);
                chi2 += z * z;
                ++used;
            }
            std::printf("  [measured] %s %s: profile chi2 %.1f over %d bins (critical %.1f)\n",
                        to_string(mode), kChannelNames[c], chi2, used,
                        testing::chi2_critical(used, alpha));
            EXPECT_LT(chi2, testing::chi2_critical(used, alpha));
        }
    }
}

TEST(VolpathSphereImage, IndexMatchedSphereSeenFromTheDarkSide) {
    // The camera opposite the light (v = -l) sees the exit points of the chords: at image radius
    // rho (in units of R) the chord has mu = sqrt(1 - rho^2), the exitance is E0 mu exp(-a mu)
    // and the light leaves along v with the flux E0 exp(-a mu) per unit image area. So the
    // "exitance" layer (M / pi) is mu exp(-a mu) / pi, and the radiance layers ("subsurface",
    // "radiance") exp(-a mu) / Omega_c, each averaged over the pixel; "specular" is 0. Per-pixel
    // z-tests over the pixels that lie wholly inside the disc; pixels wholly outside must be 0.
    const double R = 1.0;
    const double ks[3] = {0.2, 0.5, 1.5};
    Medium m = medium(0.0, 0.0, 0.0, 1.0);
    m.sigma_a_per_cm = {ks[0], ks[1], ks[2]};
    SphereScene s = scene(m, R, 18, 24);
    s.to_camera = {0, 0, -1};
    const SphereRun r = run(s, 4e5, ChromaticMode::kPerChannel, true);
    ASSERT_TRUE(r.image);
    const double omega = 2 * kPi * (1 - std::cos(s.acceptance_deg * kPi / 180));
    const double pix = 2 * s.frame_scale / s.width;  // in units of R
    const int sub = 32;
    const double alpha = testing::sidak(0.001, 9);
    const char* layers[3] = {"exitance", "subsurface", "radiance"};
    for (int c = 0; c < 3; ++c) {
        const double a = 2 * ks[c] * R;
        double chi2[3] = {0, 0, 0};
        int used = 0;
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x) {
                const double x0 = -s.frame_scale + x * pix, y0 = s.frame_scale - (y + 1) * pix;
                // Nearest and farthest points of the pixel from the centre.
                const double nx = std::clamp(0.0, x0, x0 + pix), ny = std::clamp(0.0, y0, y0 + pix);
                const double fx = std::max(std::fabs(x0), std::fabs(x0 + pix));
                const double fy = std::max(std::fabs(y0), std::fabs(y0 + pix));
                if (std::hypot(nx, ny) >= 1.0) {
                    for (const char* name : {"exitance", "subsurface", "specular", "radiance"})
                        EXPECT_EQ(r.image->layer(name).at(x, y, c), 0.0f) << x << "," << y;
                    continue;
                }
                if (std::hypot(fx, fy) >= 1.0) continue;  // on the limb
                double em = 0, rad = 0;
                for (int i = 0; i < sub; ++i)
                    for (int j = 0; j < sub; ++j) {
                        const double px = x0 + (i + 0.5) * pix / sub;
                        const double py = y0 + (j + 0.5) * pix / sub;
                        const double mu = std::sqrt(1 - px * px - py * py);
                        em += mu * std::exp(-a * mu) / kPi;
                        rad += std::exp(-a * mu) / omega;
                    }
                em /= sub * sub;
                rad /= sub * sub;
                const double expected[3] = {em, rad, rad};
                for (int l = 0; l < 3; ++l) {
                    const double v = r.image->layer(layers[l]).at(x, y, c);
                    const double se =
                        r.image->layer(std::string(layers[l]) + ".stderr").at(x, y, c);
                    ASSERT_GT(se, 0.0) << layers[l] << " " << x << "," << y;
                    const double z = z_score(v, se, expected[l]);
                    chi2[l] += z * z;
                }
                EXPECT_EQ(r.image->layer("specular").at(x, y, c), 0.0f);
                ++used;
            }
        for (int l = 0; l < 3; ++l) {
            std::printf("  [measured] %s %s: chi2 %.1f over %d pixels (critical %.1f)\n", layers[l],
                        kChannelNames[c], chi2[l], used, testing::chi2_critical(used, alpha));
            EXPECT_LT(chi2[l], testing::chi2_critical(used, alpha)) << layers[l] << " " << c;
        }
        EXPECT_GT(used, 200);
    }
}

// ---- the non-scattering dielectric sphere -----------------------------------------------------

TEST(VolpathSphereTransport, ClearDielectricSphereLetsEverythingOut) {
    // eta = 1.5, sigma = 0: no absorption, so specular + transmitted = 1 photon by photon; the
    // specular part estimates the disc average of F, which the engine also gives by quadrature.
    const double eta = 1.5;
    const SphereRun r = run(scene(medium(0.0, 0.0, 0.0, eta), 1.0), 1e5);
    const double expected = specular_by_quadrature(eta);
    EXPECT_NEAR(r.specular_expected, expected, 1e-12);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(r.diffuse[c] + r.specular[c], 1.0, 1e-12);
        EXPECT_EQ(r.lost[c], 0.0);
        expect_within(r.specular[c], r.specular_se[c], expected, z_crit(0.01, 3),
                      "clear sphere specular");
    }
    EXPECT_EQ(r.events, 0u);
}

TEST(VolpathSphereTransport, AbsorbingDielectricSphereMatchesTheInternalReflectionSeries) {
    // sigma_s = 0, absorption k, eta = 1.5. A photon entering with cosine mu refracts to the
    // cosine c, crosses chords of length 2 R c, and meets the surface every time at the same
    // angle, where the internal reflectance equals the external F(mu) (reciprocity). With
    // A = exp(-2 k R c) it leaves with probability (1 - F) A sum_j (F A)^j (1 - F), so the exit
    // fraction is int_0^1 2 mu (1 - F)^2 A / (1 - F A) dmu (Simpson here).
    const double eta = 1.5, R = 1.0;
    const double ks[3] = {0.1, 0.5, 2.0};
    Medium m = medium(0.0, 0.0, 0.0, eta);
    m.sigma_a_per_cm = {ks[0], ks[1], ks[2]};
    for (ChromaticMode mode : {ChromaticMode::kPerChannel, ChromaticMode::kHero}) {
        SCOPED_TRACE(to_string(mode));
        const SphereRun r = run(scene(m, R), 2e5, mode);
        for (int c = 0; c < 3; ++c) {
            const double k = ks[c];
            const double expected = simpson(
                [&](double mu) {
                    double cos_t = 0;
                    const double F = fresnel_dielectric(mu, eta, cos_t);
                    const double A = std::exp(-2 * k * R * cos_t);
                    return 2 * mu * (1 - F) * (1 - F) * A / (1 - F * A);
                },
                0, 1, 20000);
            expect_within(r.diffuse[c], r.diffuse_se[c], expected, z_crit(0.001, 6),
                          "absorbing dielectric sphere exit");
        }
    }
}

// ---- the specular highlight -----------------------------------------------------------------

TEST(VolpathSphereImage, SpecularHighlightHasTheMirrorSphereIntensity) {
    // A mirror sphere under a directional light reflects into the solid angle d omega_r the
    // flux F E0 R^2 d omega_r / 4 (the normals within d omega_n receive E0 R^2 cos(theta_i)
    // d omega_n, and d omega_r = 4 cos(theta_i) d omega_n), with cos(theta_i) = l . h =
    // sqrt((1 + l . omega_r) / 2). Averaged over the acceptance cone around v:
    // I = R^2 / (4 Omega_c) int_cone F domega, by quadrature here. The image layers must add up
    // to the intensities: sum over pixels of (layer x pixel area).
    const double R = 1.5, eta = 1.5;
    SphereScene s = scene(medium(0.0, 0.0, 0.0, eta), R, 18, 32);
    const double phase = 60 * kPi / 180;
    s.to_camera = {std::sin(phase), 0, std::cos(phase)};
    const SphereRun r = run(s, 1e6, ChromaticMode::kPerChannel, true);
    const double theta_c = s.acceptance_deg * kPi / 180;
    const double omega = 2 * kPi * (1 - std::cos(theta_c));
    const Vec3 l = s.to_light, v = normalize(s.to_camera);
    double integral = 0;
    const int nt = 400, np = 400;
    for (int i = 0; i < nt; ++i)
        for (int j = 0; j < np; ++j) {
            const double th = (i + 0.5) * theta_c / nt, ph = (j + 0.5) * 2 * kPi / np;
            const Vec3 w = rotate(v, std::cos(th), ph);
            const double cos_i = std::sqrt(0.5 * (1 + dot(l, w)));
            integral +=
                fresnel_dielectric(cos_i, eta) * std::sin(th) * (theta_c / nt) * (2 * kPi / np);
        }
    const double expected = R * R / (4 * omega) * integral;
    const double pix_area = std::pow(2 * s.frame_scale * R / s.width, 2);
    for (int c = 0; c < 3; ++c) {
        expect_within(r.intensity_specular[c], r.intensity_specular_se[c], expected,
                      z_crit(0.01, 3), "specular intensity [cm^2/sr]");
        // Clear sphere: the light that entered also leaves, some of it towards the camera.
        EXPECT_GT(r.intensity_subsurface[c], 0.0);
        double sums[3] = {0, 0, 0};
        const char* names[3] = {"specular", "subsurface", "radiance"};
        for (int l2 = 0; l2 < 3; ++l2) {
            double sum = 0;
            const ImageLayer& layer = r.image->layer(names[l2]);
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x) sum += layer.at(x, y, c);
            sums[l2] = sum * pix_area;
        }
        EXPECT_NEAR(sums[0], r.intensity_specular[c], 1e-5 * r.intensity_specular[c]);
        EXPECT_NEAR(sums[1], r.intensity_subsurface[c], 1e-5 * r.intensity_subsurface[c]);
        EXPECT_NEAR(sums[2], r.intensity_specular[c] + r.intensity_subsurface[c],
                    1e-5 * (r.intensity_specular[c] + r.intensity_subsurface[c]));
    }
}

// ---- hero vs per-channel, sphere vs half-space --------------------------------------------

TEST(VolpathSphereCrossValidation, HeroModeAgreesWithPerChannelRuns) {
    // A strongly chromatic medium with a different g per channel (the phase MIS weights matter).
    Medium m = medium(0, 0, 0, 1.4);
    m.sigma_a_per_cm = {0.5, 3.0, 12.0};
    m.sigma_s_per_cm = {40.0, 25.0, 60.0};
    m.g = {0.0, 0.6, -0.3};
    const SphereScene s = scene(m, 0.3, 36);
    const SphereRun a = run(s, 1e5, ChromaticMode::kPerChannel);
    const SphereRun h = run(s, 1e5, ChromaticMode::kHero);
    const double alpha = testing::sidak(0.001, 3);
    for (int c = 0; c < 3; ++c) {
        SCOPED_TRACE(kChannelNames[c]);
        testing::ZTally t;
        for (size_t j = 0; j < a.exitance[c].size(); ++j)
            t.add_pair(a.exitance[c][j], a.exitance_se[c][j], h.exitance[c][j],
                       h.exitance_se[c][j]);
        std::printf("  [measured] hero vs per-channel %s: chi2 %.1f over %d bins (critical %.1f)\n",
                    kChannelNames[c], t.chi2, t.n, testing::chi2_critical(t.n, alpha));
        EXPECT_GE(t.n, 18);  // at least the lit hemisphere (blue barely reaches the dark side)
        EXPECT_LT(t.chi2, testing::chi2_critical(t.n, alpha));
        const double z =
            (a.diffuse[c] - h.diffuse[c]) / std::hypot(a.diffuse_se[c], h.diffuse_se[c]);
        std::printf("  [measured] diffuse %.6f +- %.2g vs hero %.6f +- %.2g (z = %.2f)\n",
                    a.diffuse[c], a.diffuse_se[c], h.diffuse[c], h.diffuse_se[c], z);
        EXPECT_LT(std::fabs(z), z_crit(0.001, 3));
    }
}

TEST(VolpathSphereCrossValidation, LargeSphereSubsolarExitanceIsTheHalfSpaceReflectance) {
    // R = 1000 mean free paths: near the subsolar point (beta = 0) the sphere is a half-space
    // under uniform normal illumination E0, whose exitance is, by translation invariance,
    // E0 times the total diffuse reflectance of a pencil beam, entry factor 1 - F(0) included
    // (simulate_pencil's rd_total). The first 5-degree bin averages M over the cap; the
    // irradiance there falls as cos(beta), whose area-weighted mean over the cap is
    // (1 + cos 5 deg) / 2 = 0.9981, applied to the expectation; the same for the
    // single-scattering parts. The remaining O(beta^2)
    // dependence of the oblique-incidence reflectance, and the curvature (O(mfp / R) = 1e-3),
    // are a few 1e-3 at most, well below the standard error of ~1.7 %.
    const double sigma_t = 10.0, albedo = 0.9;
    const Medium m = medium(sigma_t * (1 - albedo), sigma_t * albedo, 0.0, 1.3);
    const SphereScene s = scene(m, 1000 / sigma_t, 36);
    const SphereRun sp = run(s, 1e6, ChromaticMode::kHero);
    PencilOptions po;
    po.budget.samples = scaled(2e5);
    po.mode = ChromaticMode::kHero;
    const PencilRun slab = simulate_pencil(m, {0.01, 10}, po);
    const double cap = 0.5 * (1 + std::cos(kPi / 36));
    for (int c = 0; c < 3; ++c) {
        const double m0 = sp.exitance[c][0], m0_se = sp.exitance_se[c][0];
        const double rd = slab.profile.rd_total[c], rd_se = slab.profile.rd_total_se[c];
        const double z = (m0 - cap * rd) / std::hypot(m0_se, cap * rd_se);
        std::printf(
            "  [measured] %s: M(beta in [0, 5 deg]) = %.5f +- %.5f vs half-space %.5f +- %.5f x "
            "%.5f (z = %.2f)\n",
            kChannelNames[c], m0, m0_se, rd, rd_se, cap, z);
        EXPECT_LT(std::fabs(z), z_crit(0.001, 6));
        // The same for the single-scattering part (paths with exactly one event).
        const double s0 = sp.exitance_single[c][0], s0_se = sp.exitance_single_se[c][0];
        const double ss = slab.single.rd_total[c], ss_se = slab.single.rd_total_se[c];
        const double zs = (s0 - cap * ss) / std::hypot(s0_se, cap * ss_se);
        std::printf(
            "  [measured] %s single scattering: %.5f +- %.5f vs half-space %.5f +- %.5f "
            "(z = %.2f)\n",
            kChannelNames[c], s0, s0_se, ss, ss_se, zs);
        EXPECT_GT(s0, 0.02 * m0);
        EXPECT_LT(s0, m0);
        EXPECT_LT(std::fabs(zs), z_crit(0.001, 6));
        EXPECT_LE(sp.diffuse_single[c], sp.diffuse[c]);
    }
    // The dark side of a sphere 1000 mean free paths across gets nothing measurable.
    EXPECT_LT(sp.exitance[0].back(), 1e-6);
}

// ---- determinism, checkpoints ---------------------------------------------------------------

TEST(VolpathSphereRuns, BitIdenticalForAnyThreadCount) {
    Medium m = *find_material("Marble");
    const SphereScene s = scene(m, 0.5, 36, 16);
    for (ChromaticMode mode : {ChromaticMode::kPerChannel, ChromaticMode::kHero}) {
        SphereOptions o;
        o.budget.samples = 12000;
        o.batch_paths = 999;
        o.mode = mode;
        o.threads = 1;
        const SphereRun one = simulate_sphere(s, o);
        o.threads = 2;
        const SphereRun two = simulate_sphere(s, o);
        ASSERT_EQ(one.runs.size(), two.runs.size());
        for (size_t i = 0; i < one.runs.size(); ++i) {
            EXPECT_EQ(one.runs[i].mean, two.runs[i].mean);
            EXPECT_EQ(one.runs[i].se, two.runs[i].se);
            EXPECT_EQ(one.runs[i].work, two.runs[i].work);
        }
    }
}

TEST(VolpathSphereRuns, SmallRunsHave32Batches) {
    // core's default_batch_samples (tested with the pencil): 2,000 paths in 32 batches of 63
    // (whole hero cycles: 32 of 63 as well, 63 = 3 x 21), not 2 of 1000.
    const SphereScene s = scene(*find_material("Marble"), 0.5);
    for (ChromaticMode mode : {ChromaticMode::kPerChannel, ChromaticMode::kHero}) {
        SphereOptions o;
        o.budget.samples = 2000;
        o.mode = mode;
        const SphereRun r = simulate_sphere(s, o);
        for (const BatchRunResult& run : r.runs) {
            EXPECT_EQ(run.batches, 32u);
            EXPECT_EQ(run.samples, 2000u);
        }
    }
}

TEST(VolpathSphereRuns, ResumeFromCheckpointEqualsAnUninterruptedRun) {
    testing::TempDir dir;
    const SphereScene s = scene(*find_material("Skin1"), 0.5, 36, 16);
    SphereOptions o;
    o.budget.samples = 60000;
    o.batch_paths = 1000;
    o.mode = ChromaticMode::kHero;
    const SphereRun full = simulate_sphere(s, o);

    std::atomic<bool> cancel{false};
    SphereOptions c = o;
    c.checkpoint_prefix = (dir / "run").string();
    c.cancel = &cancel;
    c.on_batch = [&](int, const BatchProgress& p) {
        if (p.samples >= 20000) cancel = true;
    };
    const SphereRun cut = simulate_sphere(s, c);
    EXPECT_TRUE(cut.interrupted);
    EXPECT_FALSE(cut.image);
    EXPECT_TRUE(std::filesystem::exists(dir / "run.hero.ckpt"));
    c.cancel = nullptr;
    c.on_batch = nullptr;
    const SphereRun resumed = simulate_sphere(s, c);
    EXPECT_TRUE(resumed.runs[0].resumed);
    EXPECT_EQ(resumed.runs[0].mean, full.runs[0].mean);
    EXPECT_EQ(resumed.runs[0].se, full.runs[0].se);
    // Kept until the caller has stored the result (core/batch_runner.h), then removed by it.
    EXPECT_TRUE(std::filesystem::exists(dir / "run.hero.ckpt"));
    remove_checkpoints(c.checkpoint_prefix);
    EXPECT_FALSE(std::filesystem::exists(dir / "run.hero.ckpt"));

    // A checkpoint of another run (here: another camera) is refused, not silently resumed.
    c.cancel = &cancel;
    cancel = false;
    c.on_batch = [&](int, const BatchProgress& p) {
        if (p.samples >= 5000) cancel = true;
    };
    (void)simulate_sphere(s, c);
    SphereScene other = s;
    other.to_camera = {1, 0, 0};
    c.cancel = nullptr;
    c.on_batch = nullptr;
    EXPECT_THROW(simulate_sphere(other, c), InputError);
}

// ---- stiff cases ------------------------------------------------------------------------------

TEST(VolpathSphereStiff, ExtremeMediaStayFiniteAndEnd) {
    struct Case {
        const char* what;
        Medium m;
        double radius;
    };
    const Case cases[] = {
        {"optical radius 1e-6", medium(5e-7, 5e-7, 0.0, 1.3), 1.0},
        {"optical radius 1e4, albedo 0.5", medium(5e3, 5e3, 0.0, 1.3), 1.0},
        {"albedo 1e-6", medium(10.0, 1e-5, 0.0, 1.3), 1.0},
        {"albedo 1 - 1e-9", medium(1e-8, 10.0 - 1e-8, 0.0, 1.3), 1.0},
        {"albedo 1 - 1e-9, optical radius 1e3", medium(1e-6, 1e3, 0.0, 1.3), 1.0},
        {"g = 0.999", medium(0.1, 100.0, 0.999, 1.3), 1.0},
        {"g = -0.999", medium(0.1, 100.0, -0.999, 1.3), 1.0},
        {"eta 1", medium(0.1, 10.0, 0.0, 1.0), 1.0},
        {"eta 2.5", medium(0.1, 10.0, 0.0, 2.5), 1.0},
        {"eta below 1", medium(0.1, 10.0, 0.0, 1.0, 1.4), 1.0},
        {"sigma_t = 0, eta 2.5", medium(0.0, 0.0, 0.0, 2.5), 1.0},
        {"tiny sphere", medium(1.0, 100.0, 0.8, 1.4), 1e-9},
        {"huge sphere", medium(1.0, 100.0, 0.8, 1.4), 1e6},
    };
    Medium mixed = medium(0.0, 0.0, 0.0, 1.4);  // one clear channel, one dense
    mixed.sigma_a_per_cm = {0.0, 1.0, 100.0};
    mixed.sigma_s_per_cm = {0.0, 10.0, 1000.0};
    mixed.g = {0.0, 0.5, -0.5};
    std::vector<Case> all(std::begin(cases), std::end(cases));
    all.push_back({"channels from sigma_t = 0 to 1100", mixed, 1.0});
    for (const Case& k : all) {
        SCOPED_TRACE(k.what);
        for (ChromaticMode mode : {ChromaticMode::kPerChannel, ChromaticMode::kHero}) {
            SphereScene s = scene(k.m, k.radius, 36, 16);
            s.to_camera = {0.6, 0.0, 0.8};
            const auto t0 = std::chrono::steady_clock::now();
            const SphereRun r = run(s, 3e3, mode, true);
            const double secs =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            expect_sane(r, k.what);
            const double per_path = static_cast<double>(r.events) / static_cast<double>(r.paths);
            std::printf(
                "  [measured] %-38s %-11s: %.4g events/path, %.3f s, diffuse %.4g, lost "
                "%.3g\n",
                k.what, to_string(mode), per_path, secs, r.diffuse[0], r.lost[0]);
            EXPECT_LT(per_path, 1e4);
        }
    }
}

TEST(VolpathSphereInput, InvalidInputsAreRefused) {
    const Medium ok = medium(0.1, 1.0, 0.0, 1.3);
    auto refused = [](SphereScene s) {
        SphereOptions o;
        o.budget.samples = 10;
        EXPECT_THROW(simulate_sphere(s, o), std::invalid_argument);
    };
    SphereScene s = scene(ok, 1.0);
    s.radius_cm = 0;
    refused(s);
    s.radius_cm = NAN;
    refused(s);
    refused(scene(medium(-0.1, 1.0, 0.0, 1.3), 1.0));
    refused(scene(medium(0.1, NAN, 0.0, 1.3), 1.0));
    refused(scene(medium(0.1, 1.0, 1.0, 1.3), 1.0));
    refused(scene(medium(0.1, 1.0, -1.0, 1.3), 1.0));
    refused(scene(medium(0.1, 1.0, 0.0, 0.0), 1.0));
    s = scene(ok, 1.0);
    s.to_light = {0, 0, 0};
    refused(s);
    s = scene(ok, 1.0);
    s.to_camera = {0, NAN, 1};
    refused(s);
    s = scene(ok, 1.0);
    s.up = {0, 0, 2};  // parallel to the viewing direction
    refused(s);
    s = scene(ok, 1.0);
    s.width = 0;
    refused(s);
    s = scene(ok, 1.0);
    s.acceptance_deg = 0;
    refused(s);
    s = scene(ok, 1.0);
    s.beta_bins = 0;
    refused(s);
    s = scene(ok, 1.0);
    s.width = s.height = 16384;
    SphereOptions o;
    EXPECT_THROW(simulate_sphere(s, o), InfeasibleError);
    o.image = false;  // without the image the same scene is fine
    o.budget.samples = 100;
    EXPECT_NO_THROW(simulate_sphere(s, o));
    // sigma_t = 0 is no problem in a sphere: the light crosses it.
    EXPECT_NO_THROW(run(scene(medium(0, 0, 0, 1.3), 1.0), 100));
}

TEST(VolpathSphereImage, CameraFrameIsRightHandedAndCoversTheSphere) {
    SphereScene s = scene(medium(0.1, 1.0, 0.0, 1.3), 2.0);
    s.width = 40;
    s.height = 20;
    const SphereCamera cam = sphere_camera(s);
    // Looking down -z with +y up: +x is to the right.
    EXPECT_NEAR(cam.right.x, 1.0, 1e-15);
    EXPECT_NEAR(cam.up.y, 1.0, 1e-15);
    // Square pixels; the shorter side spans [-s R, s R].
    EXPECT_NEAR(cam.pixel_cm, 2 * 1.1 * 2.0 / 20, 1e-15);
    EXPECT_NEAR(cam.half_y, 1.1 * 2.0, 1e-14);
    EXPECT_NEAR(cam.half_x, 2 * 1.1 * 2.0, 1e-14);
    // Looking along y, the default up is z with the sign that keeps +x to the right.
    for (double vy : {1.0, -1.0}) {
        s.to_camera = {0, vy, 0};
        const SphereCamera c2 = sphere_camera(s);
        EXPECT_NEAR(c2.right.x, 1.0, 1e-15) << vy;
        EXPECT_NEAR(dot(c2.up, c2.v), 0.0, 1e-15);
    }
}

}  // namespace
}  // namespace ssslab::volpath
