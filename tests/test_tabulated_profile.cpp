// approx::TabulatedProfile: a model known at radii only, interpolated in (ln r, ln R_d). Checked
// against the closed forms of the built-in models it tabulates (R_d at radii between the nodes,
// the annulus means a radial bin measures, R_dr).
#include "approx/diffusion.h"
#include "approx/tabulated_profile.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace ssslab;
using approx::TabulatedProfile;

namespace {

TabulatedProfile table_of(const approx::DiffusionProfile& p, int per_decade) {
    const approx::DiffusionMedium& m = p.medium();
    const double l = 1 / m.sigma_t_reduced(), lo = 1e-6 * l, hi = 1e6 * l;
    std::vector<double> v;
    for (double r : TabulatedProfile::radii(lo, hi, 12 * per_decade + 1)) v.push_back(p.rd(r));
    return TabulatedProfile("table", m, lo, hi, v, false);
}

}  // namespace

TEST(TabulatedProfile, MatchesTheModelItTabulatesBetweenItsNodes) {
    std::mt19937_64 rng(7);
    for (const char* model : {"dipole", "better-dipole"})
        for (const double albedo : {0.01, 0.5, 0.99, 0.999999})
            for (const double g : {-0.9, 0.0, 0.9}) {
                const approx::DiffusionMedium m{(1 - albedo) * 2.0, albedo * 2.0, g, 1.4};
                const auto exact = approx::make_diffusion_profile(model, m);
                const TabulatedProfile t = table_of(*exact, 2048);
                const double l = 1 / m.sigma_t_reduced();
                const double tr = std::sqrt(3 * m.sigma_a * m.sigma_t_reduced());
                std::uniform_real_distribution<double> u(std::log(1e-5), std::log(1e3));
                for (int k = 0; k < 200; ++k) {
                    const double r = l * std::exp(u(rng));
                    if (tr * r > 100) continue;  // the claim's range: e^{-sigma_tr r} to e^{-100}
                    const double want = exact->rd(r);
                    EXPECT_NEAR(t.rd(r) / want, 1.0, 1e-7)
                        << model << " albedo " << albedo << " g " << g << " r " << r;
                }
                EXPECT_NEAR(t.total_rd() / exact->total_rd(), 1.0, 1e-7) << model << " " << albedo;
                for (const double r0 : {0.0, 0.1 * l, 3 * l})
                    EXPECT_NEAR(t.annulus_mean(r0, r0 + l) / exact->annulus_mean(r0, r0 + l), 1.0,
                                1e-7)
                        << model << " " << albedo << " " << r0;
            }
}

TEST(TabulatedProfile, ZerosAndEndsAreHandledAsDocumented) {
    // A table that falls to zero (what float underflow gives) is linear there and 0 beyond.
    const std::vector<double> r = TabulatedProfile::radii(1.0, 1000.0, 4);  // 1, 10, 100, 1000
    EXPECT_DOUBLE_EQ(r[1], 10.0);
    EXPECT_DOUBLE_EQ(r[3], 1000.0);
    const approx::DiffusionMedium m{0.1, 1.0, 0.0, 1.0};
    const TabulatedProfile t("t", m, 1.0, 1000.0, {4.0, 2.0, 0.0, 0.0}, false);
    EXPECT_DOUBLE_EQ(t.rd(0.0), 4.0);  // R_d(r_min) below r_min
    EXPECT_DOUBLE_EQ(t.rd(0.5), 4.0);
    EXPECT_DOUBLE_EQ(t.rd(2000.0), 0.0);  // 0 beyond r_max
    EXPECT_NEAR(t.rd(100.0), 0.0, 1e-12);
    // Between 10 and 100 linear in R_d at t = (ln r - ln 10) / ln 10.
    EXPECT_NEAR(t.rd(std::sqrt(1000.0)), 1.0, 1e-12);
    // A positive table of a power law is exact in log-log: R_d = r^-2.
    const TabulatedProfile p("p", m, 1.0, 1000.0, {1.0, 1e-2, 1e-4, 1e-6}, false);
    EXPECT_NEAR(p.rd(31.622776601683793) / 1e-3, 1.0, 1e-12);
    // R_dr: pi r_min^2 R(r_min) + 2 pi int_1^1000 r^-1 dr.
    EXPECT_NEAR(p.total_rd(), M_PI + 2 * M_PI * std::log(1000.0), 1e-9);
    EXPECT_THROW(TabulatedProfile("nan", m, 1.0, 1000.0, {1.0, NAN, 1.0, 1.0}, false),
                 std::invalid_argument);
    EXPECT_THROW(TabulatedProfile::radii(1.0, 1.0, 8), std::invalid_argument);
    EXPECT_THROW(TabulatedProfile::radii(1.0, 2.0, 3), std::invalid_argument);
}
