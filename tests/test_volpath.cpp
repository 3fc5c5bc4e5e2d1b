// The volumetric path tracer (volpath/) against physics, closed forms, literature and the other
// engine (MCML): sampling and optics, the white furnace, Chandrasekhar's half-space, the ballistic
// slab, MCML bin by bin, hero vs per-channel, the boundary flight rule, determinism and
// checkpoints, and stiff cases.
#include "core/error.h"
#include "core/material.h"
#include "core/rng.h"
#include "mcml/profile.h"
#include "testing.h"
#include "volpath/pencil.h"
#include "volpath/sampling.h"
#include "volpath/walk.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace ssslab::volpath {
namespace {

std::int64_t scaled(double paths) {
    return static_cast<std::int64_t>(paths * testing::test_scale());
}

Medium slab(double mua, double mus, double g, double eta, double thickness_cm,
            double eta_out = 1.0) {
    Medium m;
    m.name = "test";
    for (int c = 0; c < 3; ++c) {
        m.sigma_a_per_cm[c] = mua;
        m.sigma_s_per_cm[c] = mus;
        m.g[c] = g;
    }
    m.eta = eta;
    m.eta_above = m.eta_below = eta_out;
    m.thickness_cm = thickness_cm;
    return m;
}

PencilRun run(const Medium& m, double paths, ChromaticMode mode = ChromaticMode::kPerChannel,
              PencilGrid grid = {0.01, 50}, FlightRule rule = FlightRule::kContinue,
              int threads = 0) {
    PencilOptions o;
    o.budget.samples = scaled(paths);
    o.mode = mode;
    o.flight = rule;
    o.threads = threads;
    return simulate_pencil(m, grid, o);
}

void expect_within(double value, double se, double expected, double k, const char* what) {
    EXPECT_TRUE(std::isfinite(value)) << what;
    EXPECT_LE(std::fabs(value - expected), k * se + 1e-15)
        << what << ": " << value << " +- " << se << " vs " << expected
        << " (z = " << (value - expected) / se << ")";
}

// ---- sampling and optics --------------------------------------------------------------------

// HG CDF in mu: (1 - g^2) / (2 g) ((1 + g^2 - 2 g mu)^(-1/2) - 1 / (1 + g)), (1 + mu) / 2 at g = 0.
double hg_cdf(double g, double mu) {
    if (g == 0) return 0.5 * (1 + mu);
    return (1 - g * g) / (2 * g) * (1 / std::sqrt(1 + g * g - 2 * g * mu) - 1 / (1 + g));
}

TEST(VolpathSampling, HenyeyGreensteinChiSquare) {
    // 1e6 samples into 100 cells of equal probability (cell edges by bisection on the CDF).
    const double gs[] = {-0.999, -0.9, -0.3, 0.0, 1e-9, 0.5, 0.9, 0.999};
    const double alpha = testing::sidak(0.01, 8);
    int id = 0;
    for (double g : gs) {
        SCOPED_TRACE(g);
        const int cells = 100;
        std::vector<double> edges(cells + 1);
        edges[0] = -1;
        edges[cells] = 1;
        for (int k = 1; k < cells; ++k) {
            double lo = -1, hi = 1;
            for (int it = 0; it < 200; ++it) {
                const double mid = 0.5 * (lo + hi);
                (hg_cdf(g, mid) < double(k) / cells ? lo : hi) = mid;
            }
            edges[static_cast<size_t>(k)] = 0.5 * (lo + hi);
        }
        RngStream rng(7, rng_domain::kTest + 200 + static_cast<std::uint32_t>(id++), 0);
        const std::int64_t n = scaled(1e6);
        std::vector<double> obs(cells, 0.0), expct(cells, static_cast<double>(n) / cells);
        for (std::int64_t i = 0; i < n; ++i) {
            const double mu = sample_hg(g, rng.uniform());
            ASSERT_TRUE(mu >= -1 && mu <= 1);
            const auto it = std::upper_bound(edges.begin(), edges.end(), mu);
            const long k = std::clamp<long>(it - edges.begin() - 1, 0, cells - 1);
            obs[static_cast<size_t>(k)] += 1;
        }
        int dof = 0;
        const double chi2 = testing::chi2_statistic(obs, expct, dof);
        EXPECT_LT(chi2, testing::chi2_critical(dof, alpha)) << "dof " << dof;
    }
}

TEST(VolpathSampling, HenyeyGreensteinDensityIntegratesToOneAndMatchesMean) {
    // int p dOmega = 1 and <mu> = g, by midpoint quadrature in t with mu = +-(1 - 2 t^2),
    // which puts the nodes densely at the forward (or backward) peak.
    for (double g : {-0.99, -0.5, 0.0, 0.7, 0.99}) {
        const int n = 2'000'000;
        const double sign = g < 0 ? -1.0 : 1.0;
        double norm = 0, mean = 0;
        for (int i = 0; i < n; ++i) {
            const double t = (i + 0.5) / n;
            const double mu = sign * (1 - 2 * t * t);
            const double p = 2 * kPi * hg_pdf(g, mu) * 4 * t / n;
            norm += p;
            mean += p * mu;
        }
        EXPECT_NEAR(norm, 1.0, 1e-5) << g;
        EXPECT_NEAR(mean, g, 1e-5) << g;
    }
}

TEST(VolpathOptics, FresnelReciprocityEnergyAndLimits) {
    for (double eta : {0.4, 0.7, 1.0 / 1.33, 1.0, 1.33, 1.5, 2.5}) {
        SCOPED_TRACE(eta);
        // Normal incidence: ((eta - 1) / (eta + 1))^2.
        EXPECT_NEAR(fresnel_dielectric(1.0, eta), std::pow((eta - 1) / (eta + 1), 2), 1e-15);
        for (int i = 0; i <= 1000; ++i) {
            const double cos_i = i / 1000.0;
            double cos_t = 0;
            const double F = fresnel_dielectric(cos_i, eta, cos_t);
            ASSERT_TRUE(F >= 0 && F <= 1);
            const double sin_i = std::sqrt(1 - cos_i * cos_i);
            if (sin_i / eta >= 1) {
                EXPECT_EQ(F, 1.0);  // total internal reflection
                continue;
            }
            // Snell.
            EXPECT_NEAR(eta * std::sqrt(1 - cos_t * cos_t), sin_i, 1e-12);
            // Energy: R + T = 1 with T from the transmission amplitudes.
            if (cos_i > 0) {
                const double ts = 2 * cos_i / (cos_i + eta * cos_t);
                const double tp = 2 * cos_i / (eta * cos_i + cos_t);
                const double T = eta * cos_t / cos_i * 0.5 * (ts * ts + tp * tp);
                EXPECT_NEAR(F + T, 1.0, 1e-12) << cos_i;
            }
            // Reciprocity: the same reflectance seen from the other side.
            if (cos_t > 0) {
                double back = 0;
                EXPECT_NEAR(fresnel_dielectric(cos_t, 1 / eta, back), F, 1e-12) << cos_i;
                EXPECT_NEAR(back, cos_i, 1e-9);
            }
            // The refracted direction is a unit vector with the cosine cos_t.
            if (cos_i > 0) {
                const Vec3 d{sin_i, 0, -cos_i}, n{0, 0, 1};
                const Vec3 t = refract(d, n, eta, cos_t);
                EXPECT_NEAR(length(t), 1.0, 1e-14);
                EXPECT_NEAR(-t.z, cos_t, 1e-12);
            }
        }
    }
    EXPECT_EQ(fresnel_dielectric(0.3, 1.0), 0.0);  // index-matched: no reflection at all
}

TEST(VolpathOptics, RotatedDirectionsHaveTheRequestedCosine) {
    RngStream rng(3, rng_domain::kTest + 210, 0);
    for (int i = 0; i < 100000; ++i) {
        const Vec3 w = rotate(Vec3{0, 0, 1}, 2 * rng.uniform() - 1, 2 * kPi * rng.uniform());
        const double mu = 2 * rng.uniform() - 1;
        const Vec3 v = rotate(w, mu, 2 * kPi * rng.uniform());
        ASSERT_NEAR(length(v), 1.0, 1e-13);
        ASSERT_NEAR(dot(v, w), mu, 1e-12);
    }
}

// ---- transport against closed forms and literature ---------------------------------------

TEST(VolpathWeights, ScatteringIsTheBalanceHeuristicOverEachChannelsOwnDensity) {
    // One scattering collision at distance d: whichever channel is the hero, channel c's weight
    // is the one-sample balance heuristic f_c / sum_k P_k p_k with f_c = sigma_s,c T_c(d) and
    // p_k the density of strategy k: sigma_s,k T_k(d) if it absorbs by roulette (analog),
    // sigma_t,k T_k(d) if it weights its absorption. Per channel: albedos 0.95, 0.5, 0.17 give
    // weighted, weighted (0.5 is the threshold), analog.
    using namespace ssslab::volpath;
    const std::array<double, 3> st{1.05, 6.0, 48.0}, ss{1.0, 3.0, 8.0};
    const WalkRegion r = WalkRegion::make(st, ss, {0.0, 0.5, 0.9});
    const std::array<double, 3> P{0.5, 0.3, 0.2};
    const double d = 0.07;
    for (const Absorption a :
         {Absorption::kAnalog, Absorption::kWeighted, Absorption::kPerChannel}) {
        const bool weighted[3] = {a != Absorption::kAnalog, a != Absorption::kAnalog,
                                  a == Absorption::kWeighted};
        double mix = 0;
        for (int k = 0; k < 3; ++k)
            mix += P[static_cast<size_t>(k)] *
                   (weighted[k] ? st[static_cast<size_t>(k)] : ss[static_cast<size_t>(k)]) *
                   std::exp(-st[static_cast<size_t>(k)] * d);
        for (int h = 0; h < 3; ++h) {
            SpectralWeights<3> w;
            w.start(1.0);
            w.prob = P;
            w.hero = h;
            w.scatter(r, d, a);
            for (int c = 0; c < 3; ++c) {
                const double f =
                    ss[static_cast<size_t>(c)] * std::exp(-st[static_cast<size_t>(c)] * d);
                EXPECT_NEAR(w.beta[c], f / mix, 1e-12 * f / mix)
                    << to_string(a) << " hero " << h << " channel " << c;
            }
            // The mixture of the densities stays 1 (the rescaling).
            EXPECT_NEAR(P[0] * w.q[0] + P[1] * w.q[1] + P[2] * w.q[2], 1.0, 1e-12);
        }
    }
    EXPECT_EQ(channel_absorption(Absorption::kPerChannel, 0.5), Absorption::kWeighted);
    EXPECT_EQ(channel_absorption(Absorption::kPerChannel, 0.4999), Absorption::kAnalog);
    EXPECT_EQ(channel_absorption(Absorption::kAnalog, 0.99), Absorption::kAnalog);
}

TEST(VolpathTransport, WhiteFurnaceIndexMatchedSlabLosesNothing) {
    // Albedo 1, no index change: every path leaves the slab, R + T = 1 for each path in analog
    // mode (exactly), and within its standard error in hero mode, where the channels differ.
    const Medium m = slab(0.0, 20.0, 0.5, 1.0, 0.5);
    const PencilRun a = run(m, 2e4);
    for (int c = 0; c < 3; ++c) {
        EXPECT_DOUBLE_EQ(a.profile.rd_total[c] + a.tt[c], 1.0);
        EXPECT_GT(a.profile.rd_total[c], 0.1);
    }
    Medium chroma = m;
    chroma.sigma_s_per_cm = {5.0, 20.0, 60.0};
    chroma.g = {0.0, 0.5, 0.9};
    const PencilRun h = run(chroma, 3e4, ChromaticMode::kHero);
    for (int c = 0; c < 3; ++c) {
        const double sum = h.profile.rd_total[c] + h.tt[c];
        // The per-path sum varies with the MIS weights; its SE is at most the sum of the SEs.
        expect_within(sum, h.profile.rd_total_se[c] + h.tt_se[c], 1.0, 4, kChannelNames[c]);
    }
}

TEST(VolpathTransport, ChandrasekharHalfSpaceReflectance) {
    // Index-matched isotropic half-space at normal incidence: R = 1 - H(1) sqrt(1 - a), H
    // computed in the test (testing::chandrasekhar_h). First a check of H itself: a = 0.9 gives
    // the tabulated 0.414947 (Prahl et al. 1989).
    EXPECT_NEAR(1 - testing::chandrasekhar_h(0.9, 1.0) * std::sqrt(0.1), 0.414947, 2e-6);
    const double alpha = testing::sidak(0.01, 4);
    const double k = testing::normal_quantile(1 - alpha / 2);
    for (double a : {0.3, 0.8, 0.95, 0.99}) {
        SCOPED_TRACE(a);
        const Medium m = slab(1.0 - a, a, 0.0, 1.0, 1e8);
        const PencilRun r = run(m, 2e5);
        const double expected = 1 - testing::chandrasekhar_h(a, 1.0) * std::sqrt(1 - a);
        for (int c = 0; c < 3; ++c)
            expect_within(r.profile.rd_total[c], r.profile.rd_total_se[c], expected, k, "Rd");
    }
}

TEST(VolpathTransport, BallisticSlabMatchesTheAiryFormula) {
    // sigma_s = 0: a beam bouncing between the faces. With R = ((n - 1) / (n + 1))^2 and
    // A = exp(-tau): T = (1 - R)^2 A / (1 - R^2 A^2), diffuse R_d = (1 - R)^2 R A^2 / (1 - R^2 A^2)
    // (the specular Rsp = R is not in R_d), all of it in the first radial bin.
    const double n = 1.5, tau = 0.7;
    const Medium m = slab(tau, 0.0, 0.0, n, 1.0);
    const PencilRun r = run(m, 2e5);
    const double R = std::pow((n - 1) / (n + 1), 2), A = std::exp(-tau);
    const double T = (1 - R) * (1 - R) * A / (1 - R * R * A * A);
    const double Rd = (1 - R) * (1 - R) * R * A * A / (1 - R * R * A * A);
    for (int c = 0; c < 3; ++c) {
        expect_within(r.tt[c], r.tt_se[c], T, 4, "T");
        expect_within(r.profile.rd_total[c], r.profile.rd_total_se[c], Rd, 4, "Rd");
        EXPECT_EQ(r.profile.beyond[c], 0.0);
        EXPECT_EQ(r.profile.rsp[c], R);
    }
}

TEST(VolpathTransport, GiovanelliSemiInfiniteN15) {
    // Semi-infinite, albedo 0.9, isotropic, n = 1.5 in air: total reflectance Rsp + Rd = 0.2600
    // (Giovanelli 1955; Prahl et al. 1989: 0.26079 +- 0.00079). Internal reflection matters
    // here (72 % of the upward flux at the boundary is reflected back at n = 1.5).
    const Medium m = slab(10, 90, 0.0, 1.5, 1e8);
    for (Absorption a : {Absorption::kAnalog, Absorption::kWeighted}) {
        PencilOptions o;
        o.budget.samples = scaled(2e5);
        o.absorption = a;
        const PencilRun r = simulate_pencil(m, {0.01, 50}, o);
        EXPECT_DOUBLE_EQ(r.profile.rsp[0], 0.04);
        expect_within(r.profile.rsp[0] + r.profile.rd_total[0], r.profile.rd_total_se[0], 0.2600, 4,
                      "Rsp + Rd");
    }
}

TEST(VolpathTransport, VanDeHulstSlab) {
    // tau = 2, albedo 0.9, g = 0.75, matched boundaries: Rd = 0.09739, Tt = 0.66096 (van de
    // Hulst 1980, as in Wang et al. 1995 Table 2). Tt here includes the unscattered beam.
    const Medium m = slab(10, 90, 0.75, 1.0, 0.02);
    const PencilRun r = run(m, 2e5);
    for (int c = 0; c < 3; ++c) {
        expect_within(r.profile.rd_total[c], r.profile.rd_total_se[c], 0.09739, 4, "Rd");
        expect_within(r.tt[c], r.tt_se[c], 0.66096, 4, "Tt");
    }
}

// ---- against MCML ----------------------------------------------------------------------------

struct BinComparison {
    double chi2 = 0, max_abs_z = 0;
    int bins = 0;
};

// Per-bin z-scores of two independent profiles with standard errors; only bins where both are
// well estimated (relative SE below 30 %) enter, so Gaussian statistics apply.
BinComparison compare(const RadialProfile& a, const RadialProfile& b, int c) {
    BinComparison out;
    for (size_t i = 0; i < a.rd_per_cm2[c].size(); ++i) {
        const double sa = a.se_per_cm2[c][i], sb = b.se_per_cm2[c][i];
        const double va = a.rd_per_cm2[c][i], vb = b.rd_per_cm2[c][i];
        if (!(sa > 0 && sb > 0) || sa > 0.3 * va || sb > 0.3 * vb) continue;
        const double z = (va - vb) / std::sqrt(sa * sa + sb * sb);
        out.chi2 += z * z;
        out.max_abs_z = std::max(out.max_abs_z, std::fabs(z));
        ++out.bins;
    }
    return out;
}

TEST(VolpathCrossValidation, AgreesWithMcmlOnTheSkin1RedProfile) {
    // The acceptance test: Skin1 (Freude14 Table 6.2), red channel, on a grid of 100
    // bins of 0.02 cm: every bin within 4 sigma, overall chi-square p > 0.001.
    const Medium skin = *find_material("Skin1");
    const mcml::ProfileGrid g{0.02, 100};
    mcml::ProfileOptions mo;
    mo.budget.samples = scaled(2e5);
    const mcml::ProfileRun ref = mcml::simulate_profile(skin, g, mo);
    const PencilRun vp = run(skin, 2e5, ChromaticMode::kPerChannel, {g.dr_cm, g.nr});
    const BinComparison cmp = compare(vp.profile, ref.profile, 0);
    std::printf(
        "Skin1 R: chi2 %.1f over %d bins, max |z| %.2f; Rd %.6f +- %.6f vs MCML %.6f +- %.6f\n",
        cmp.chi2, cmp.bins, cmp.max_abs_z, vp.profile.rd_total[0], vp.profile.rd_total_se[0],
        ref.profile.rd_total[0], ref.profile.rd_total_se[0]);
    EXPECT_GT(cmp.bins, 60);
    EXPECT_LT(cmp.max_abs_z, 4.0);
    EXPECT_LT(cmp.chi2, testing::chi2_critical(cmp.bins, 0.001)) << cmp.bins << " bins";
    const double z = (vp.profile.rd_total[0] - ref.profile.rd_total[0]) /
                     std::hypot(vp.profile.rd_total_se[0], ref.profile.rd_total_se[0]);
    EXPECT_LT(std::fabs(z), 4.0) << vp.profile.rd_total[0] << " vs " << ref.profile.rd_total[0];
}

TEST(VolpathCrossValidation, HeroModeAgreesWithPerChannelRuns) {
    // Analog, weighted and hero estimators (analog and weighted hero, uniform and mfp hero
    // selection) on a strongly chromatic medium with a different g per channel (the phase MIS
    // weights matter).
    Medium m = slab(0, 0, 0, 1.4, 1e8);
    m.sigma_a_per_cm = {0.5, 3.0, 12.0};
    m.sigma_s_per_cm = {40.0, 25.0, 60.0};
    m.g = {0.0, 0.6, -0.3};
    const PencilGrid grid{0.01, 60};
    const PencilRun a = run(m, 1e5, ChromaticMode::kPerChannel, grid);
    const PencilRun h = run(m, 1e5, ChromaticMode::kHero, grid);
    PencilOptions wo;
    wo.budget.samples = scaled(1e5);
    wo.absorption = Absorption::kWeighted;
    const PencilRun wt = simulate_pencil(m, grid, wo);
    PencilOptions ho;
    ho.budget.samples = scaled(1e5);
    ho.mode = ChromaticMode::kHero;
    ho.hero_selection = HeroSelection::kMeanFreePath;
    const PencilRun hm = simulate_pencil(m, grid, ho);
    ho.hero_selection = HeroSelection::kUniform;
    ho.absorption = Absorption::kWeighted;
    const PencilRun hw = simulate_pencil(m, grid, ho);
    const double alpha = testing::sidak(0.001, 3);
    for (int c = 0; c < 3; ++c) {
        SCOPED_TRACE(kChannelNames[c]);
        const BinComparison chw = compare(a.profile, hw.profile, c);
        EXPECT_LT(chw.chi2, testing::chi2_critical(chw.bins, alpha)) << chw.bins << " bins";
        const BinComparison cm = compare(a.profile, hm.profile, c);
        EXPECT_LT(cm.chi2, testing::chi2_critical(cm.bins, alpha)) << cm.bins << " bins";
        const BinComparison cw = compare(a.profile, wt.profile, c);
        EXPECT_LT(cw.chi2, testing::chi2_critical(cw.bins, alpha)) << cw.bins << " bins";
        const BinComparison cmp = compare(a.profile, h.profile, c);
        EXPECT_GT(cmp.bins, 10);
        EXPECT_LT(cmp.chi2, testing::chi2_critical(cmp.bins, alpha)) << cmp.bins << " bins";
        const double z = (a.profile.rd_total[c] - h.profile.rd_total[c]) /
                         std::hypot(a.profile.rd_total_se[c], h.profile.rd_total_se[c]);
        EXPECT_LT(std::fabs(z), 4.0);
    }
}

TEST(VolpathCrossValidation, FlightRuleAfterInternalReflection) {
    // Continuing the sampled free path and drawing a fresh one agree (the exponential is
    // memoryless); interacting at the reflection point instead is biased, by a clear margin on a
    // medium where internal reflection matters (n = 1.5).
    const Medium m = slab(0.5, 50.0, 0.0, 1.5, 1e8);
    const PencilGrid grid{0.01, 40};
    const PencilRun cont = run(m, 2e5, ChromaticMode::kPerChannel, grid, FlightRule::kContinue);
    const PencilRun fresh = run(m, 2e5, ChromaticMode::kPerChannel, grid, FlightRule::kResample);
    const PencilRun inter =
        run(m, 2e5, ChromaticMode::kPerChannel, grid, FlightRule::kInteractAtBoundary);
    const BinComparison same = compare(cont.profile, fresh.profile, 0);
    EXPECT_LT(same.chi2, testing::chi2_critical(same.bins, 0.001)) << same.bins;
    auto z = [](const PencilRun& x, const PencilRun& y) {
        return (x.profile.rd_total[0] - y.profile.rd_total[0]) /
               std::hypot(x.profile.rd_total_se[0], y.profile.rd_total_se[0]);
    };
    std::printf(
        "Rd continue %.5f +- %.5f, resample %.5f +- %.5f, interact at boundary %.5f +- %.5f\n",
        cont.profile.rd_total[0], cont.profile.rd_total_se[0], fresh.profile.rd_total[0],
        fresh.profile.rd_total_se[0], inter.profile.rd_total[0], inter.profile.rd_total_se[0]);
    EXPECT_LT(std::fabs(z(cont, fresh)), 4.0);
    EXPECT_GT(std::fabs(z(cont, inter)), 10.0)
        << cont.profile.rd_total[0] << " vs " << inter.profile.rd_total[0];
}

// ---- determinism, checkpoints ---------------------------------------------------------------

TEST(VolpathRuns, BitIdenticalForAnyThreadCount) {
    const Medium m = *find_material("Marble");
    for (ChromaticMode mode : {ChromaticMode::kPerChannel, ChromaticMode::kHero}) {
        const PencilRun one = run(m, 1e4, mode, {0.01, 50}, FlightRule::kContinue, 1);
        const PencilRun two = run(m, 1e4, mode, {0.01, 50}, FlightRule::kContinue, 2);
        ASSERT_EQ(one.runs.size(), two.runs.size());
        for (size_t i = 0; i < one.runs.size(); ++i) {
            EXPECT_EQ(one.runs[i].mean, two.runs[i].mean);
            EXPECT_EQ(one.runs[i].se, two.runs[i].se);
            EXPECT_EQ(one.runs[i].work, two.runs[i].work);
        }
    }
}

TEST(VolpathRuns, SmallRunsReportStandardErrorsFrom32Batches) {
    // The default batch size (core's default_batch_samples, MCML's rule): a run of n < 32,000
    // paths has 32 batches, from 32,000 on batches of n / 1000.
    EXPECT_EQ(default_batch_samples(SampleBudget{2000, {}, {}}), 63);
    EXPECT_EQ(default_batch_samples(SampleBudget{31999, {}, {}}), 1000);
    EXPECT_EQ(default_batch_samples(SampleBudget{32000, {}, {}}), 1000);
    EXPECT_EQ(default_batch_samples(SampleBudget{10'000'000, {}, {}}), 10000);
    EXPECT_EQ(default_batch_samples(SampleBudget{{}, 5.0, {}}), 1000);
    EXPECT_EQ(default_batch_samples(SampleBudget{{}, {}, {}}, 640), 20);
    EXPECT_EQ(default_batch_samples(SampleBudget{{}, 5.0, {}}, 640), 1000);
    // What it is for: a 2,000-path run's standard error is worth its name. Chandrasekhar's
    // isotropic half-space (albedo 0.8, index-matched, normal incidence: R = 1 - H(1) sqrt(1-a))
    // in 60 seeded runs of 2,000 paths, three independent channels each: z = (Rd - R) / SE. With
    // 32 batches z follows Student's t with 31 degrees of freedom, P(|z| > 3) = 0.0053, so more
    // than 8 of 180 has probability 1e-6. With 2 batches (the engines' old default for this
    // budget: batches of 1000) z is t with one degree of freedom, P(|z| > 3) = 0.205: fewer than
    // 15 of 180 has probability below 1e-6, so the check below tells the two apart.
    const double a = 0.8;
    const Medium m = slab(1.0 - a, a, 0.0, 1.0, 1e8);
    const double expected = 1 - testing::chandrasekhar_h(a, 1.0) * std::sqrt(1 - a);
    auto count_beyond_3 = [&](std::int64_t batch_paths, std::int64_t expected_batches) {
        int beyond = 0;
        for (std::uint64_t seed = 1; seed <= 60; ++seed) {
            PencilOptions o;
            o.seed = seed;
            o.budget.samples = 2000;
            o.batch_paths = batch_paths;
            const PencilRun r = simulate_pencil(m, {0.01, 50}, o);
            for (int c = 0; c < 3; ++c) {
                EXPECT_EQ(r.runs[c].batches, static_cast<std::uint64_t>(expected_batches));
                const double z = (r.profile.rd_total[c] - expected) / r.profile.rd_total_se[c];
                beyond += std::fabs(z) > 3;
            }
        }
        return beyond;
    };
    const int with_32 = count_beyond_3(0, 32), with_2 = count_beyond_3(1000, 2);
    std::printf("|z| > 3 in 180 runs of 2,000 paths: %d with 32 batches, %d with 2\n", with_32,
                with_2);
    EXPECT_LE(with_32, 8) << "the default batch size";
    EXPECT_GE(with_2, 15) << "two batches (the old default)";
}

TEST(VolpathRuns, ResumeFromCheckpointEqualsAnUninterruptedRun) {
    testing::TempDir dir;
    const Medium m = *find_material("Skin1");
    PencilOptions o;
    o.budget.samples = 60000;
    o.batch_paths = 1000;
    o.mode = ChromaticMode::kHero;
    const PencilRun full = simulate_pencil(m, {0.01, 50}, o);

    std::atomic<bool> cancel{false};
    PencilOptions c = o;
    c.checkpoint_prefix = (dir / "run").string();
    c.cancel = &cancel;
    c.on_batch = [&](int, const BatchProgress& p) {
        if (p.samples >= 20000) cancel = true;
    };
    const PencilRun cut = simulate_pencil(m, {0.01, 50}, c);
    EXPECT_TRUE(cut.interrupted);
    EXPECT_TRUE(std::filesystem::exists(dir / "run.hero.ckpt"));
    c.cancel = nullptr;
    c.on_batch = nullptr;
    const PencilRun resumed = simulate_pencil(m, {0.01, 50}, c);
    EXPECT_TRUE(resumed.runs[0].resumed);
    EXPECT_EQ(resumed.runs[0].mean, full.runs[0].mean);
    EXPECT_EQ(resumed.runs[0].se, full.runs[0].se);
    // Kept until the caller has stored the result (core/batch_runner.h), then removed by it.
    EXPECT_TRUE(std::filesystem::exists(dir / "run.hero.ckpt"));
    remove_checkpoints(c.checkpoint_prefix);
    EXPECT_FALSE(std::filesystem::exists(dir / "run.hero.ckpt"));

    // A checkpoint of another run is refused, not silently resumed.
    c.cancel = &cancel;
    cancel = false;
    c.on_batch = [&](int, const BatchProgress& p) {
        if (p.samples >= 5000) cancel = true;
    };
    (void)simulate_pencil(m, {0.01, 50}, c);
    PencilOptions other = c;
    other.seed = 2;
    other.cancel = nullptr;
    other.on_batch = nullptr;
    EXPECT_THROW(simulate_pencil(m, {0.01, 50}, other), InputError);
}

// ---- stiff cases -----------------------------------------------------------------------------

void expect_sane(const PencilRun& r, const char* what) {
    for (int c = 0; c < 3; ++c) {
        for (const auto* p : {&r.profile, &r.single}) {
            for (double v : p->rd_per_cm2[c]) ASSERT_TRUE(std::isfinite(v) && v >= 0) << what;
            for (double v : p->se_per_cm2[c]) ASSERT_TRUE(std::isfinite(v) && v >= 0) << what;
        }
        EXPECT_TRUE(std::isfinite(r.profile.rd_total[c]) && r.profile.rd_total[c] >= 0) << what;
        EXPECT_TRUE(std::isfinite(r.tt[c]) && r.tt[c] >= 0) << what;
    }
}

TEST(VolpathStiff, ExtremeAlbedoAnisotropyAndIndex) {
    struct Case {
        const char* what;
        Medium m;
    };
    const Case cases[] = {
        {"albedo 1e-6", slab(1.0, 1e-6, 0.0, 1.3, 1e8)},
        {"albedo 1 - 1e-9", slab(1e-8, 10.0 - 1e-8, 0.0, 1.3, 1e8)},
        {"albedo 1 - 1e-9 thin", slab(1e-8, 10.0, 0.0, 1.3, 0.5)},
        {"g = 0.999", slab(0.1, 100.0, 0.999, 1.3, 1e8)},
        {"g = -0.999", slab(0.1, 100.0, -0.999, 1.3, 1e8)},
        {"eta 2.5", slab(0.1, 10.0, 0.0, 2.5, 1e8)},
        {"eta below 1", slab(0.1, 10.0, 0.0, 1.0, 1e8, 1.4)},
        {"tiny lengths", slab(1e5, 1e7, 0.0, 1.3, 1e8)},
        {"huge lengths", slab(1e-5, 1e-3, 0.0, 1.3, 1e8)},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.what);
        for (ChromaticMode mode : {ChromaticMode::kPerChannel, ChromaticMode::kHero}) {
            const PencilRun r = run(c.m, 2e3, mode, {0.01, 50});
            expect_sane(r, c.what);
        }
    }
    // Albedo 1 - 1e-9 in a half-space: paths of unbounded mean length (the return time of a
    // random walk to a plane has infinite mean). The long-path roulette bounds them: the mean
    // path length stays finite. Its survivors (weight 10^k) must walk back from a depth of
    // ~sqrt(1e4) mean free paths, which takes ~1e4 further events, each another 10 % roulette:
    // they practically never return, so the estimate behaves like a truncation and falls short
    // of R = 1 - H(1) sqrt(1 - a) (H(1) = 2.90781 at a = 1, Chandrasekhar 1950, Table XXI) by
    // the mass that reached the roulette, which the `lost` tally measures (at albedo ~1 nearly
    // all of it would have returned).
    const Medium white = slab(1e-9, 1.0 - 1e-9, 0.0, 1.0, 1e8);
    PencilOptions wo;
    wo.budget.samples = scaled(2e4);
    wo.long_path_events = 10000;
    const PencilRun w = simulate_pencil(white, {0.01, 50}, wo);
    expect_sane(w, "white half-space");
    EXPECT_LT(static_cast<double>(w.events) / static_cast<double>(w.paths), 3000.0);
    const double expected = 1 - 2.90781 * std::sqrt(1e-9);
    const double rd = w.profile.rd_total[0], se = w.profile.rd_total_se[0];
    EXPECT_LT(rd, expected + 4 * se);
    EXPECT_GT(w.lost[0], 0.0);
    const double z = (rd + w.lost[0] - expected) / std::hypot(se, w.lost_se[0]);
    std::printf(
        "white half-space: Rd %.6f +- %.6f, lost %.6f +- %.6f, expected %.6f, %.0f events/path\n",
        rd, se, w.lost[0], w.lost_se[0], expected,
        static_cast<double>(w.events) / static_cast<double>(w.paths));
    EXPECT_LT(std::fabs(z), 4.0) << rd << " + lost " << w.lost[0] << " vs " << expected;
}

TEST(VolpathStiff, InfeasibleAndInvalidInputsAreRefused) {
    EXPECT_THROW(simulate_pencil(slab(0, 0, 0, 1.3, 1e8), {0.01, 10}, {}), InfeasibleError);
    EXPECT_THROW(simulate_pencil(slab(0.1, 1, 1.0, 1.3, 1e8), {0.01, 10}, {}),
                 std::invalid_argument);
    EXPECT_THROW(simulate_pencil(slab(-0.1, 1, 0, 1.3, 1e8), {0.01, 10}, {}),
                 std::invalid_argument);
    EXPECT_THROW(simulate_pencil(slab(0.1, 1, 0, 1.3, 1e8), {0.0, 10}, {}), std::invalid_argument);
    EXPECT_THROW(simulate_pencil(slab(0.1, NAN, 0, 1.3, 1e8), {0.01, 10}, {}),
                 std::invalid_argument);
}

}  // namespace
}  // namespace ssslab::volpath
