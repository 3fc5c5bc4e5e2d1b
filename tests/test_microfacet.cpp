// The GGX rough dielectric (volpath/microfacet.h) against closed forms and its own sampler:
// normalisation of D and of the visible-normal density, a chi-square test of the sampled
// directions against the density the renderer uses for MIS, energy (single-scattering albedo at
// most 1, tending to 1 as the roughness vanishes), the smooth limit (reflection with the Fresnel
// probability) and radiance compression across the boundary.
#include "core/rng.h"
#include "testing.h"
#include "volpath/microfacet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace ssslab::volpath {
namespace {

Vec3 dir(double cos_theta, double phi) {
    const double s = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
    return {s * std::cos(phi), s * std::sin(phi), cos_theta};
}

TEST(Microfacet, DistributionAndVisibleNormalsAreNormalised) {
    for (double alpha : {0.01, 0.1, 0.5, 1.0}) {
        SCOPED_TRACE(alpha);
        // int D(m) cos(theta_m) dm = 1: x = tan^2 / alpha^2 from 0 to inf, u = x / (1 + x).
        double sum = 0;
        const int n = 200000;
        for (int i = 0; i < n; ++i) {
            const double u = (i + 0.5) / n, x = u / (1 - u), dx = 1 / ((1 - u) * (1 - u)) / n;
            const double mu = 1 / std::sqrt(1 + alpha * alpha * x);
            const double dmu = 0.5 * alpha * alpha * std::pow(1 + alpha * alpha * x, -1.5) * dx;
            sum += 2 * kPi * ggx::D(dir(mu, 0), alpha) * mu * dmu;
        }
        EXPECT_NEAR(sum, 1.0, 1e-6);
        // int D_visible(w, m) dm = 1 for several w (midpoint rule in cos(theta_m), phi).
        for (double cw : {1.0, 0.7, 0.2}) {
            const Vec3 w = dir(cw, 0.3);
            double s = 0;
            const int nt = 2000, np = 256;
            for (int i = 0; i < nt; ++i)
                for (int j = 0; j < np; ++j) {
                    // cos(theta_m) = 1 - v^2 puts points where D peaks for small alpha.
                    const double v = (i + 0.5) / nt, mu = 1 - v * v, dmu = 2 * v / nt;
                    const Vec3 m = dir(mu, 2 * kPi * (j + 0.5) / np);
                    if (dot(w, m) > 0)  // the visible ones
                        s += ggx::D_visible(w, m, alpha) * dmu * 2 * kPi / np;
                }
            EXPECT_NEAR(s, 1.0, alpha < 0.05 ? 2e-2 : 2e-3) << "cos w " << cw;
        }
    }
}

TEST(Microfacet, SampledDirectionsFollowTheDensityChiSquare) {
    // pbrt-v4's BSDF chi-square test: sampled wi binned over the sphere (cos theta x phi)
    // against the density integrated over each bin; bins with fewer than 5 expected samples
    // pooled. Also the total probability of a valid sample.
    const int nt = 20, np = 40;
    const std::int64_t n = static_cast<std::int64_t>(1e6 * testing::test_scale());
    int test_id = 0;
    for (double alpha : {0.2, 0.6}) {
        for (double eta : {1.5, 1.0 / 1.33}) {
            for (double cw : {0.9, 0.3, -0.6}) {
                SCOPED_TRACE("alpha " + std::to_string(alpha) + " eta " + std::to_string(eta) +
                             " cos wo " + std::to_string(cw));
                const Vec3 wo = dir(cw, 1.0);
                RngStream rng(3, rng_domain::kTest + 60, static_cast<std::uint64_t>(test_id++));
                std::vector<double> observed(nt * np, 0.0), expected(nt * np, 0.0);
                for (std::int64_t k = 0; k < n; ++k) {
                    const auto s =
                        sample_rough_dielectric(wo, eta, alpha, rng.uniform(), rng.uniform(),
                                                rng.uniform(), TransportMode::kRadiance);
                    if (!s) continue;
                    const int it = std::min(nt - 1, static_cast<int>((s->wi.z + 1) / 2 * nt));
                    double phi = std::atan2(s->wi.y, s->wi.x);
                    if (phi < 0) phi += 2 * kPi;
                    const int ip = std::min(np - 1, static_cast<int>(phi / (2 * kPi) * np));
                    observed[static_cast<size_t>(it * np + ip)] += 1;
                }
                // Expected counts by a midpoint rule on sub x sub points per bin: its error (the
                // density has sharp lobes and the TIR edge) must stay below the sampling noise,
                // which falls with the sample count (16 is enough for 1e6 samples, 96 for 1e7).
                const int sub = testing::test_scale() > 2 ? 96 : 16;
                double total = 0;
                for (int it = 0; it < nt; ++it)
                    for (int ip = 0; ip < np; ++ip) {
                        double e = 0;
                        for (int a = 0; a < sub; ++a)
                            for (int b = 0; b < sub; ++b) {
                                const double c = -1 + 2.0 * (it + (a + 0.5) / sub) / nt;
                                const double p = 2 * kPi * (ip + (b + 0.5) / sub) / np;
                                e += rough_dielectric_pdf(wo, dir(c, p), eta, alpha);
                            }
                        e *= (2.0 / nt) * (2 * kPi / np) / (sub * sub);
                        expected[static_cast<size_t>(it * np + ip)] = e * static_cast<double>(n);
                        total += e;
                    }
                double obs_total = 0;
                for (double o : observed) obs_total += o;
                // Valid fraction: the density integrates to it (within sampling noise and the
                // quadrature's error).
                EXPECT_NEAR(obs_total / static_cast<double>(n), total, 5e-3);
                int dof = 0;
                const double chi2 = testing::chi2_statistic(observed, expected, dof);
                EXPECT_LT(chi2, testing::chi2_critical(dof, testing::sidak(0.01, 12)))
                    << dof << " bins";
            }
        }
    }
}

TEST(Microfacet, EnergyAndTheSmoothLimit) {
    RngStream rng(4, rng_domain::kTest + 61, 0);
    const std::int64_t n = 400000;
    for (double cw : {0.95, 0.5, 0.15}) {
        for (double eta : {1.5, 1.0 / 1.5}) {
            SCOPED_TRACE("cos wo " + std::to_string(cw) + " eta " + std::to_string(eta));
            const Vec3 wo = dir(cw, 0.2);
            for (double alpha : {0.001, 0.1, 0.3, 1.0}) {
                double sum = 0, sum2 = 0, refl = 0, rad = 0;
                for (std::int64_t k = 0; k < n; ++k) {
                    const double uc = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                    const auto s = sample_rough_dielectric(wo, eta, alpha, uc, u1, u2,
                                                           TransportMode::kImportance);
                    if (!s) continue;
                    const double wgt = s->f * std::abs(s->wi.z) / s->pdf;
                    sum += wgt;
                    sum2 += wgt * wgt;
                    refl += s->reflection;
                    const auto r = sample_rough_dielectric(wo, eta, alpha, uc, u1, u2,
                                                           TransportMode::kRadiance);
                    if (r) rad += r->f * std::abs(r->wi.z) / r->pdf;
                }
                const double mean = sum / n,
                             se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
                // Single scattering between microfacets: never more than 1; for alpha -> 0 all.
                EXPECT_LE(mean, 1.0 + 4 * se + 1e-12) << alpha;
                if (alpha <= 0.001) {
                    EXPECT_GT(mean, 0.999) << alpha;
                }
                // From the optically thinner side the loss is small up to alpha = 0.3; from
                // the denser side, beyond the critical angle, rays reflected below the surface
                // by single microfacet TIR are lost (no multiple scattering in the model).
                if (alpha <= 0.3 && eta > 1) {
                    EXPECT_GT(mean, 0.85) << alpha;
                }
                if (alpha <= 0.001) {
                    // The smooth limit: reflection with Fresnel's probability, and radiance mode
                    // divides the transmitted part by eta^2.
                    const double F = fresnel_dielectric(cw, eta);
                    const double p = refl / n;
                    EXPECT_NEAR(p, F, 4 * std::sqrt(F * (1 - F) / n) + 2e-3);
                    EXPECT_NEAR(rad / n, F + (1 - F) / (eta * eta), 3e-3);
                }
            }
        }
    }
}

}  // namespace
}  // namespace ssslab::volpath
