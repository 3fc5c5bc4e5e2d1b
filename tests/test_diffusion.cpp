// Diffusion profiles (approx/diffusion.h) against closed forms, physics and quadratures written
// here independently of the library (composite Simpson rules, pbrt's BeamDiffusionMS/SS retyped
// from pbrt-v4's source). Tolerances are stated with their reason next to each check.
#include "approx/diffusion.h"
#include "approx/diffusion_detail.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace ssslab::approx {
namespace {

constexpr double kPi = 3.14159265358979323846;
const double kInf = std::numeric_limits<double>::infinity();

// ---- Independent numerics -----------------------------------------------------------------------

// Composite Simpson's rule with n (even) intervals.
double simpson(const std::function<double(double)>& f, double a, double b, int n) {
    const double h = (b - a) / n;
    double s = f(a) + f(b);
    for (int i = 1; i < n; ++i) s += f(a + i * h) * (i % 2 ? 4 : 2);
    return s * h / 3;
}

struct Estimate {
    double value;  // Simpson with n intervals
    double error;  // |S_n - S_{n/2}|: about 15x the error of S_n for a smooth integrand
};

// 2 pi int_0^inf R(r) r dr = int 2 pi r^2 R d(ln r) over [lo, hi] by Simpson, plus the piece
// [0, lo] as for R ~ 1/r, 2 pi lo^2 R(lo) (exact for 1/r, an overestimate by a factor ~2 for
// log(1/r) or finite profiles, where it is ~lo^2 and negligible at lo = 1e-10 mean free paths).
Estimate profile_total(const std::function<double(double)>& rd, double lo, double hi, int n) {
    auto f = [&](double x) {
        const double r = std::exp(x);
        return 2 * kPi * r * r * rd(r);
    };
    const double head = 2 * kPi * lo * lo * rd(lo);
    const double fine = simpson(f, std::log(lo), std::log(hi), n);
    const double coarse = simpson(f, std::log(lo), std::log(hi), n / 2);
    return {fine + head, std::abs(fine - coarse)};
}

// Fresnel reflectance from inside (relative index eta = n_in / n_out), written out here.
double fresnel(double mu, double eta) {
    const double s2 = eta * eta * (1 - mu * mu);
    if (s2 >= 1) return 1.0;
    const double ct = std::sqrt(1 - s2);
    const double rs = (eta * mu - ct) / (eta * mu + ct), rp = (mu - eta * ct) / (mu + eta * ct);
    return 0.5 * (rs * rs + rp * rp);
}

// C_i = int_0^1 F(mu) mu^i dmu by Simpson: below the critical cosine F = 1 exactly; above it,
// in the variable w = sqrt(mu - mu_c), which removes the square-root kink of F at mu_c.
double moment(int i, double eta) {
    const double mu_c = eta > 1 ? std::sqrt(1 - 1 / (eta * eta)) : 0.0;
    const double tir = std::pow(mu_c, i + 1) / (i + 1);
    const double w1 = std::sqrt(1 - mu_c);
    return tir + simpson(
                     [&](double w) {
                         const double mu = mu_c + w * w;
                         return fresnel(mu, eta) * std::pow(mu, i) * 2 * w;
                     },
                     0, w1, 200000);
}

// Henyey-Greenstein in pbrt's convention (argument: cosine between outward directions).
double phase_hg(double cos_theta, double g) {
    const double denom = 1 + g * g + 2 * g * cos_theta;
    return (1 - g * g) / (4 * kPi * denom * std::sqrt(denom));
}

DiffusionMedium medium(double albedo, double g, double eta, double thickness = kInf) {
    DiffusionMedium m;
    m.sigma_a = 1 - albedo;
    m.sigma_s = albedo;
    m.g = g;
    m.eta = eta;
    m.thickness = thickness;
    return m;
}

// ---- Fresnel helpers ----------------------------------------------------------------------------

TEST(DiffusionFresnel, ExactMomentsMatchAnIndependentQuadrature) {
    // Simpson with 2e5 intervals on a smooth integrand: error far below 1e-10.
    for (double eta : {0.5, 0.7, 0.95, 1.05, 1.3, 1.5, 2.0, 2.5}) {
        const FresnelMomentPair c = fresnel_moments(eta, FresnelMoments::exact);
        EXPECT_NEAR(c.c1, moment(1, eta), 1e-10) << "eta " << eta;
        EXPECT_NEAR(c.c2, moment(2, eta), 1e-10) << "eta " << eta;
    }
    const FresnelMomentPair one = fresnel_moments(1.0, FresnelMoments::exact);
    EXPECT_EQ(one.c1, 0.0);
    EXPECT_EQ(one.c2, 0.0);
    EXPECT_EQ(classical_reflection_parameter(1.0, FresnelMoments::exact), 1.0);
    EXPECT_EQ(better_reflection_parameter(1.0, FresnelMoments::exact), 1.0);
}

TEST(DiffusionFresnel, ExactDiffuseReflectanceObeysReciprocity) {
    // Etendue: the hemispherical transmittance from inside is the one from outside over eta^2,
    // 1 - F_dr(eta) = (1 - F_dr(1/eta)) / eta^2, for the exact Fresnel equations.
    for (double eta : {1.1, 1.3, 1.5, 2.0, 2.5}) {
        const double inside = fresnel_diffuse_reflectance(eta, FresnelMoments::exact);
        const double outside = fresnel_diffuse_reflectance(1 / eta, FresnelMoments::exact);
        EXPECT_NEAR(1 - inside, (1 - outside) / (eta * eta), 1e-13) << "eta " << eta;
    }
}

TEST(DiffusionFresnel, FitsAgreeWithTheExactMomentsToTheirAccuracy) {
    // The fits are approximations (measured worst: Egan-Hilgeman 0.7 % near eta = 1.05, d'Eon's
    // C1 0.8 %, C2 11 % at 1.05); these bounds are guards against a mistyped coefficient, which
    // moves a polynomial by far more than them.
    for (double eta : {1.2, 1.3, 1.5, 2.0}) {
        const double exact = fresnel_diffuse_reflectance(eta, FresnelMoments::exact);
        EXPECT_NEAR(fresnel_diffuse_reflectance(eta, FresnelMoments::fit) / exact, 1, 0.01);
    }
    for (double eta : {0.4, 0.6, 0.8, 0.9, 1.2, 1.5, 2.0, 2.5}) {
        const FresnelMomentPair fit = fresnel_moments(eta, FresnelMoments::fit);
        const FresnelMomentPair exact = fresnel_moments(eta, FresnelMoments::exact);
        EXPECT_NEAR(fit.c1 / exact.c1, 1, 0.01) << "eta " << eta;
        EXPECT_NEAR(fit.c2 / exact.c2, 1, 0.05) << "eta " << eta;
    }
    // [Bitterli13 Eq. 2.30] at eta = 1.3, by hand: -1.44/1.69 + 0.71/1.3 + 0.668 + 0.08268.
    EXPECT_NEAR(fresnel_diffuse_reflectance(1.3, FresnelMoments::fit),
                -1.44 / 1.69 + 0.71 / 1.3 + 0.668 + 0.0636 * 1.3, 1e-15);
    EXPECT_NEAR(normal_incidence_transmittance(1.5), 0.96, 1e-15);  // R_sp = (0.5/2.5)^2
}

// ---- Totals against the profiles ----------------------------------------------------------------

struct TotalCase {
    std::string model;
    DiffusionMedium m;
    DiffusionOptions o;
};

std::vector<TotalCase> total_cases() {
    std::vector<TotalCase> cases;
    for (const std::string& model : diffusion_model_names()) {
        const bool slow = model == "pbd";  // its profile is itself an adaptive integral
        for (double albedo : {0.3, 0.9, 0.99})
            for (double eta : {0.7, 1.3})
                for (double g : {0.0, 0.6}) {
                    if (slow && g != 0 && albedo != 0.9) continue;
                    const double t = model == "multipole" ? 3.0 : kInf;  // mfp = 1/sigma_t'
                    DiffusionMedium m = medium(albedo, g, eta);
                    m.thickness = t / m.sigma_t_reduced();
                    cases.push_back({model, m, {}});
                }
    }
    DiffusionOptions exact;
    exact.fresnel = FresnelMoments::exact;
    for (const std::string model : {"dipole", "better-dipole", "qd", "pbd"})
        cases.push_back({model, medium(0.95, 0.0, 1.5), exact});
    // Slabs without absorption (the far field is the eigenmodes' regime) and thin ones.
    for (double t : {0.2, 1.0, 5.0}) cases.push_back({"multipole", medium(1.0, 0.0, 1.3, t), {}});
    cases.push_back({"multipole", medium(0.9, 0.0, 1.3, 0.05), {}});
    DiffusionOptions pbrt;
    pbrt.pbd_depth_samples = 100;
    cases.push_back({"pbd", medium(0.8, 0.3, 1.33), pbrt});
    return cases;
}

TEST(DiffusionTotals, EachModelsTotalIsTheIntegralOfItsProfile) {
    std::map<std::string, double> worst;
    for (const TotalCase& c : total_cases()) {
        const auto p = make_diffusion_profile(c.model, c.m, c.o);
        const double mfp = 1 / c.m.sigma_t_reduced();
        const int n = c.model == "pbd" ? 1200 : 4000;
        // Every profile here has decayed by e^{-30} or more (or as 1/r^3) by 1e4 mean free paths.
        const Estimate e =
            profile_total([&](double r) { return p->rd(r); }, 1e-10 * mfp, 1e4 * mfp, n);
        const double rel = std::abs(p->total_rd() - e.value) / e.value;
        // Simpson's own error (bounded by the coarse-fine difference) plus rounding.
        EXPECT_LE(std::abs(p->total_rd() - e.value), e.error + 1e-11 * e.value)
            << c.model << " albedo " << c.m.albedo() << " g " << c.m.g << " eta " << c.m.eta;
        worst[c.model] = std::max(worst[c.model], rel);
        if (c.model == "multipole") {
            const auto* mp = dynamic_cast<const Multipole*>(p.get());
            ASSERT_NE(mp, nullptr);
            const Estimate t =
                profile_total([&](double r) { return mp->td(r); }, 1e-10 * mfp, 1e4 * mfp, n);
            EXPECT_LE(std::abs(mp->total_td() - t.value), t.error + 1e-11 * t.value)
                << "T, thickness " << c.m.thickness << " albedo " << c.m.albedo();
            worst["multipole T"] =
                std::max(worst["multipole T"], std::abs(mp->total_td() - t.value) / t.value);
        }
    }
    for (const auto& [model, rel] : worst)
        std::printf("  max |total - integral| / integral  %-20s %.2e\n", model.c_str(), rel);
}

// ---- Classical dipole ---------------------------------------------------------------------------

TEST(DiffusionDipole, TotalIsTheClosedFormOfBitterli13Eq32) {
    for (double eta : {1.0, 1.3, 1.5, 2.5}) {
        // A from [Bitterli13 Eq. 2.30], typed here.
        const double fdr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
        const double a = (1 + fdr) / (1 - fdr);
        for (double ap : {0.0, 0.1, 0.5, 0.9, 0.999, 1 - 1e-9, 1.0}) {
            DiffusionMedium m;
            m.sigma_s = ap * 2.5;  // sigma_t' = 2.5 / L: the total does not depend on the scale
            m.sigma_a = (1 - ap) * 2.5;
            m.eta = eta;
            const double t = std::sqrt(3 * (1 - ap));
            const double expected = ap / 2 * (1 + std::exp(-4.0 / 3.0 * a * t)) * std::exp(-t);
            EXPECT_NEAR(ClassicalDipole(m).total_rd(), expected, 1e-15 * (1 + expected))
                << "alpha' " << ap << " eta " << eta;
        }
    }
}

TEST(DiffusionDipole, ProfileIsJensensFormula) {
    // [Bitterli13 Eq. 2.37] typed here, D = 1/(3 sigma_t'), z_v = z_r + 4 A D.
    const DiffusionMedium m = medium(0.9, 0.2, 1.3);
    const double st = m.sigma_t_reduced(), ap = m.reduced_albedo();
    const double str = std::sqrt(3 * m.sigma_a * st), zr = 1 / st;
    const double fdr = -1.440 / 1.69 + 0.710 / 1.3 + 0.668 + 0.0636 * 1.3;
    const double zv = zr * (1 + 4.0 / 3.0 * (1 + fdr) / (1 - fdr));
    const ClassicalDipole p(m);
    for (double r : {0.0, 0.01, 0.3, 1.0, 4.0, 20.0}) {
        const double dr = std::sqrt(r * r + zr * zr), dv = std::sqrt(r * r + zv * zv);
        const double expected = ap / (4 * kPi) *
                                ((str * dr + 1) * std::exp(-str * dr) / (st * dr * dr * dr) +
                                 zv * (str * dv + 1) * std::exp(-str * dv) / (dv * dv * dv));
        EXPECT_NEAR(p.rd(r), expected, 1e-14 * expected) << "r " << r;
    }
}

// ---- Better dipole ------------------------------------------------------------------------------

TEST(DiffusionBetterDipole, ConservesEnergyWithoutAbsorption) {
    // At sigma_a = 0: R_dr = C_E + 2 C_phi A = (1 - 3 C2)/2 + (1 + 3 C2)/2 = 1, for any moments.
    for (FresnelMoments mode : {FresnelMoments::fit, FresnelMoments::exact})
        for (double eta : {0.7, 1.0, 1.3, 2.5}) {
            DiffusionOptions o;
            o.fresnel = mode;
            EXPECT_NEAR(BetterDipole(medium(1.0, 0.3, eta), o).total_rd(), 1.0, 1e-14) << eta;
        }
}

TEST(DiffusionBetterDipole, ProfileIsDEonsFormula) {
    // [dEon12] as appleseed writes it, typed here: alpha'^2/(4 pi) [(C_E z (1 + s d)/d^2 +
    // C_phi/D) e^{-s d}/d]_r - [...]_v with Grosjean's D.
    for (double eta : {0.7, 1.3}) {
        const DiffusionMedium m = medium(0.8, 0.4, eta);
        const FresnelMomentPair c = fresnel_moments(eta, FresnelMoments::fit);
        const double st = m.sigma_t_reduced(), ap = m.reduced_albedo();
        const double d = (2 * m.sigma_a + m.sigma_s_reduced()) / (3 * st * st);
        const double s = std::sqrt(m.sigma_a / d), a = (1 + 3 * c.c2) / (1 - 2 * c.c1);
        const double cphi = 0.25 * (1 - 2 * c.c1), ce = 0.5 * (1 - 3 * c.c2);
        const double zr = 1 / st, zv = -zr - 4 * a * d;
        const BetterDipole p(m);
        for (double r : {0.0, 0.05, 0.5, 2.0, 10.0}) {
            const double dr = std::sqrt(r * r + zr * zr), dv = std::sqrt(r * r + zv * zv);
            const double kr = ce * zr * (s * dr + 1) / (dr * dr) + cphi / d;
            const double kv = ce * zv * (s * dv + 1) / (dv * dv) + cphi / d;
            const double expected =
                ap * ap / (4 * kPi) * (kr * std::exp(-s * dr) / dr - kv * std::exp(-s * dv) / dv);
            EXPECT_NEAR(p.rd(r), expected, 1e-13 * expected) << "r " << r << " eta " << eta;
        }
    }
}

// ---- Multipole ----------------------------------------------------------------------------------

TEST(DiffusionMultipole, ThickSlabIsTheDipole) {
    for (MultipoleSource source : {MultipoleSource::paper, MultipoleSource::truncated})
        for (double albedo : {0.5, 0.99}) {
            DiffusionMedium m = medium(albedo, 0.0, 1.3, 1e3);  // 1e3 mean free paths
            DiffusionOptions o;
            o.multipole_source = source;
            const Multipole slab(m, o);
            m.thickness = kInf;
            const ClassicalDipole dipole(m);
            const Multipole infinite(m, o);
            // The bottom's images are e^{-sigma_tr 2 d} away: nothing left in double.
            // (Up to rounding: the slab's totals are geometric series in closed form.)
            EXPECT_NEAR(slab.total_rd(), dipole.total_rd(), 4e-15 * dipole.total_rd());
            EXPECT_NEAR(infinite.total_rd(), dipole.total_rd(), 4e-15 * dipole.total_rd());
            EXPECT_EQ(infinite.total_td(), 0.0);
            for (double r : {0.0, 0.01, 0.3, 1.0, 3.0, 10.0}) {
                EXPECT_NEAR(slab.rd(r), dipole.rd(r), 1e-14 * dipole.rd(r)) << "r " << r;
                EXPECT_NEAR(infinite.rd(r), dipole.rd(r), 1e-15 * dipole.rd(r)) << "r " << r;
            }
        }
}

TEST(DiffusionMultipole, ConservativeSlabSplitsLikeOneDimensionalDiffusion) {
    // Without absorption the diffusion flux from a plane source at depth z0 splits in inverse
    // proportion to the distances to the extrapolated boundaries: R = (d + z_b - z0) / L,
    // T = (z0 + z_b) / L, L = d + 2 z_b, times the source strength.
    for (double eta : {0.7, 1.3})
        for (double t : {0.01, 0.1, 2.0, 10.0, 1e4}) {
            const double fdr = eta >= 1 ? -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
                                        : fresnel_diffuse_reflectance(eta, FresnelMoments::fit);
            const double zb = 2 * (1 + fdr) / (1 - fdr) / 3;  // sigma_t' = 1
            const double a = -std::expm1(-t), z0 = t < 1e-4 ? t / 2 : 1 - t / std::expm1(t);
            const Multipole slab(medium(1.0, 0.0, eta, t));
            EXPECT_NEAR(slab.total_rd(), a * (t + zb - z0) / (t + 2 * zb), 1e-14) << t;
            EXPECT_NEAR(slab.total_td(), a * (z0 + zb) / (t + 2 * zb), 1e-14) << t;
            if (t > 1) {
                DiffusionOptions paper;
                paper.multipole_source = MultipoleSource::paper;
                const Multipole p(medium(1.0, 0.0, eta, t), paper);
                EXPECT_NEAR(p.total_rd(), (t + zb - 1) / (t + 2 * zb), 1e-14) << t;
                EXPECT_NEAR(p.total_td(), (1 + zb) / (t + 2 * zb), 1e-14) << t;
            }
        }
}

TEST(DiffusionMultipole, ConvergesToTheDipoleAsTheSlabThickens) {
    const double dipole = ClassicalDipole(medium(0.99, 0.0, 1.3)).total_rd();
    double previous = kInf;
    for (double t : {1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0}) {
        const Multipole slab(medium(0.99, 0.0, 1.3, t));
        const double gap = std::abs(slab.total_rd() - dipole);
        EXPECT_LT(gap, previous) << "thickness " << t;
        EXPECT_LE(slab.total_rd(), dipole) << "thickness " << t;  // light leaks out below
        previous = gap;
    }
    EXPECT_LT(previous, 1e-3);
}

TEST(DiffusionMultipole, ThinSlabsAreSensible) {
    // Truncated source: R, T >= 0, R + T <= alpha' (1 - e^{-d}) -> 0 as d -> 0, R grows with d.
    double previous_r = 0;
    for (double t : {1e-6, 1e-3, 0.05, 0.3, 1.0, 3.0}) {
        const Multipole slab(medium(0.9, 0.0, 1.3, t));
        const double bound = 0.9 * -std::expm1(-t);
        EXPECT_GE(slab.total_rd(), 0.0);
        EXPECT_GE(slab.total_td(), 0.0);
        EXPECT_LE(slab.total_rd() + slab.total_td(), bound * (1 + 1e-12)) << t;
        EXPECT_GT(slab.total_rd(), previous_r) << t;
        previous_r = slab.total_rd();
    }
    // For thick slabs transmission falls with thickness.
    EXPECT_GT(Multipole(medium(0.9, 0.0, 1.3, 2.0)).total_td(),
              Multipole(medium(0.9, 0.0, 1.3, 4.0)).total_td());
    DiffusionOptions paper;
    paper.multipole_source = MultipoleSource::paper;
    EXPECT_THROW(Multipole(medium(0.9, 0.0, 1.3, 0.5), paper), std::invalid_argument);
}

TEST(DiffusionMultipole, TotalsMatchTheEigenmodeSeries) {
    // A second representation, typed here: the slab's Green's function between the extrapolated
    // boundaries (width L) in sin modes integrates to R = (2a/L) sum_n k_n cos(k_n z_b)
    // sin(k_n zeta0) / (s^2 + k_n^2), T the same with (-1)^{n+1}, k_n = n pi / L. With
    // cos(b) sin(c) = (sin(c + b) + sin(c - b))/2 and k/(s^2 + k^2) = 1/k - s^2/(k (s^2 + k^2)),
    // the slow part is sum sin(n x)/n = (pi - x)/2 on (0, 2 pi) (alternating: x/2 on (-pi, pi));
    // the rest falls like 1/n^3 and is summed to 1e5 terms (tail ~1e-11).
    const double eta = 1.3;
    for (double t : {0.5, 2.0})
        for (double albedo : {0.5, 0.95}) {
            const DiffusionMedium m = medium(albedo, 0.0, eta, t);
            const double fdr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
            const double zb = 2 * (1 + fdr) / (1 - fdr) / 3;  // 2 A D, D = 1/3 (sigma_t' = 1)
            const double a = albedo * -std::expm1(-t), z0 = 1 - t / std::expm1(t);
            const double s2 = 3 * m.sigma_a, len = t + 2 * zb;
            auto series = [&](double x, bool alternating) {
                double rest = 0;
                for (int k = 1; k <= 100000; ++k) {
                    const double kn = k * kPi / len;
                    const double sign = alternating && k % 2 == 0 ? -1.0 : 1.0;
                    rest += sign * std::sin(k * x) / (kn * (s2 + kn * kn));
                }
                const double slow = alternating ? x / 2 : (kPi - x) / 2;
                return len / kPi * slow - s2 * rest;
            };
            const double x1 = kPi * (z0 + 2 * zb) / len, x2 = kPi * z0 / len;
            const double r = a / len * (series(x1, false) + series(x2, false));
            const double tr = a / len * (series(x1, true) + series(x2, true));
            const Multipole slab(m);
            EXPECT_NEAR(slab.total_rd(), r, 1e-10) << albedo << " " << t;
            EXPECT_NEAR(slab.total_td(), tr, 1e-10) << albedo << " " << t;
        }
}

// ---- Quantized diffusion ------------------------------------------------------------------------

// The continuous-time limit of QD: the better dipole integrated along the beam (no kappa), typed
// here. Its total by Simpson in ln z of sigma_t' e^{-sigma_t' z} alpha'^2 R_bd(z), R_bd the
// better dipole's total for a real source at depth z.
double extended_better_dipole_total(const DiffusionMedium& m) {
    const FresnelMomentPair c = fresnel_moments(m.eta, FresnelMoments::fit);
    const double st = m.sigma_t_reduced(), ap = m.reduced_albedo();
    const double d = (2 * m.sigma_a + m.sigma_s_reduced()) / (3 * st * st);
    const double s = std::sqrt(m.sigma_a / d), a = (1 + 3 * c.c2) / (1 - 2 * c.c1);
    const double cphi = 0.25 * (1 - 2 * c.c1), ce = 0.5 * (1 - 3 * c.c2);
    auto total_at = [&](double z) {
        const double zv = z + 4 * a * d;
        return 0.5 * (ce * (std::exp(-s * z) + std::exp(-s * zv)) +
                      cphi / (d * s) * (std::exp(-s * z) - std::exp(-s * zv)));
    };
    return simpson(
        [&](double x) {
            const double z = std::exp(x);
            return z * st * std::exp(-st * z) * ap * ap * total_at(z);
        },
        std::log(1e-12 / st), std::log(60 / st), 200000);
}

TEST(DiffusionQd, IsASumOfUnitMassGaussians) {
    const QuantizedDiffusion q(medium(0.9, 0.0, 1.3));
    double sum = 0, peak = 0;
    for (size_t i = 0; i < q.weights().size(); ++i) {
        sum += q.weights()[i];
        peak += q.weights()[i] / (2 * kPi * q.variances()[i]);
        EXPECT_GT(q.weights()[i], 0.0);
    }
    EXPECT_NEAR(q.total_rd(), sum, 1e-15);
    EXPECT_NEAR(q.rd(0), peak, 1e-13 * peak);
    EXPECT_TRUE(QuantizedDiffusion(medium(0.0, 0.0, 1.3)).weights().empty());
}

TEST(DiffusionQd, ConvergesToTheExtendedSourceBetterDipole) {
    // Midpoint quantisation on a geometric time grid is second order in h = ln(ratio): the error
    // must fall by ~4 from ratio 1.1 to 1.05 (a floor from the first width, 1e-4 mfp, keeps it
    // from exactly 4), and at the paper's ratio stay below the midpoint bound h^2/8.
    for (double albedo : {0.5, 0.9, 0.99}) {
        const DiffusionMedium m = medium(albedo, 0.0, 1.3);
        const double ext = extended_better_dipole_total(m);
        DiffusionOptions o;
        o.qd_first_width = 1e-4;
        o.qd_ratio = 1.1;
        const double e1 = std::abs(QuantizedDiffusion(m, o).total_rd() / ext - 1);
        o.qd_ratio = 1.05;
        const double e2 = std::abs(QuantizedDiffusion(m, o).total_rd() / ext - 1);
        EXPECT_GT(e1 / e2, 2.5) << albedo;
        EXPECT_LT(e1 / e2, 5.0) << albedo;
        const double h = std::log(DiffusionOptions{}.qd_ratio);
        const double e0 = std::abs(QuantizedDiffusion(m).total_rd() / ext - 1);
        EXPECT_LT(e0, h * h / 8) << albedo;
        std::printf(
            "  qd total vs continuous, albedo %.2f: ratio 1.618 %.2e, 1.1 %.2e, 1.05 %.2e\n",
            albedo, e0, e1, e2);
    }
}

// ---- Photon beam diffusion ----------------------------------------------------------------------

// pbrt-v4's BeamDiffusionMS and BeamDiffusionSS (src/pbrt/bssrdf.cpp), retyped in double with
// its FresnelMoment1/2 (pbrt-v3 src/core/bssrdf.cpp) and FrDielectric.
double pbrt_moment1(double eta) {
    const double e2 = eta * eta, e3 = e2 * eta, e4 = e3 * eta, e5 = e4 * eta;
    if (eta < 1)
        return 0.45966 - 1.73965 * eta + 3.37668 * e2 - 3.904945 * e3 + 2.49277 * e4 - 0.68441 * e5;
    return -4.61686 + 11.1136 * eta - 10.4646 * e2 + 5.11455 * e3 - 1.27198 * e4 + 0.12746 * e5;
}

double pbrt_moment2(double eta) {
    const double e2 = eta * eta, e3 = e2 * eta, e4 = e3 * eta, e5 = e4 * eta;
    if (eta < 1)
        return 0.27614 - 0.87350 * eta + 1.12077 * e2 - 0.65095 * e3 + 0.07883 * e4 + 0.04860 * e5;
    const double r_eta = 1 / eta, r_eta2 = r_eta * r_eta, r_eta3 = r_eta2 * r_eta;
    return -547.033 + 45.3087 * r_eta3 - 218.725 * r_eta2 + 458.843 * r_eta + 404.557 * eta -
           189.519 * e2 + 54.9327 * e3 - 9.00603 * e4 + 0.63942 * e5;
}

// One depth of BeamDiffusionMS: rho'^2 kappa (C_phi phi_D + C_E E_Dn) for the real source at zr.
double pbrt_ms_at(double sigma_s, double sigma_a, double g, double eta, double r, double zr) {
    const double sigmap_s = sigma_s * (1 - g), sigmap_t = sigma_a + sigmap_s;
    const double rhop = sigmap_s / sigmap_t;
    const double d_g = (2 * sigma_a + sigmap_s) / (3 * sigmap_t * sigmap_t);
    const double sigma_tr = std::sqrt(sigma_a / d_g);
    const double fm1 = pbrt_moment1(eta), fm2 = pbrt_moment2(eta);
    const double ze = -2 * d_g * (1 + 3 * fm2) / (1 - 2 * fm1);
    const double c_phi = 0.25 * (1 - 2 * fm1), c_e = 0.5 * (1 - 3 * fm2);
    const double zv = -zr + 2 * ze;
    const double dr = std::sqrt(r * r + zr * zr), dv = std::sqrt(r * r + zv * zv);
    const double phi_d =
        1 / (4 * kPi) / d_g * (std::exp(-sigma_tr * dr) / dr - std::exp(-sigma_tr * dv) / dv);
    const double ed_n = 1 / (4 * kPi) *
                        (zr * (1 + sigma_tr * dr) * std::exp(-sigma_tr * dr) / (dr * dr * dr) -
                         zv * (1 + sigma_tr * dv) * std::exp(-sigma_tr * dv) / (dv * dv * dv));
    const double e = phi_d * c_phi + ed_n * c_e;
    const double kappa = 1 - std::exp(-2 * sigmap_t * (dr + zr));
    return kappa * rhop * rhop * e;
}

double pbrt_ms(double sigma_s, double sigma_a, double g, double eta, double r, int n) {
    const double sigmap_t = sigma_a + sigma_s * (1 - g);
    double ed = 0;
    for (int i = 0; i < n; ++i) {
        const double zr = -std::log(1 - (i + 0.5) / n) / sigmap_t;
        ed += pbrt_ms_at(sigma_s, sigma_a, g, eta, r, zr);
    }
    return ed / n;
}

double pbrt_fr_dielectric(double cos_theta_i, double eta) {
    if (cos_theta_i < 0) {  // pbrt-v4: flip to the other side
        eta = 1 / eta;
        cos_theta_i = -cos_theta_i;
    }
    const double sin2_i = 1 - cos_theta_i * cos_theta_i, sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1) return 1.0;
    const double cos_t = std::sqrt(1 - sin2_t);
    const double r_parl = (eta * cos_theta_i - cos_t) / (eta * cos_theta_i + cos_t);
    const double r_perp = (cos_theta_i - eta * cos_t) / (cos_theta_i + eta * cos_t);
    return (r_parl * r_parl + r_perp * r_perp) / 2;
}

double pbrt_ss(double sigma_s, double sigma_a, double g, double eta, double r, int n) {
    const double sigma_t = sigma_a + sigma_s, rho = sigma_s / sigma_t;
    const double t_crit = r * std::sqrt(std::max(0.0, eta * eta - 1));
    double ess = 0;
    for (int i = 0; i < n; ++i) {
        const double ti = t_crit - std::log(1 - (i + 0.5) / n) / sigma_t;
        const double d = std::sqrt(r * r + ti * ti), cos_o = ti / d;
        ess += rho * std::exp(-sigma_t * (d + t_crit)) / (d * d) * phase_hg(cos_o, g) *
               (1 - pbrt_fr_dielectric(-cos_o, eta)) * std::abs(cos_o);
    }
    return ess / n;
}

TEST(DiffusionPbd, PbrtRuleMatchesPbrtsBeamDiffusion) {
    // Same formula and samples; only rounding (log vs log1p, expm1 rewrites) differs.
    DiffusionOptions o;
    o.pbd_depth_samples = 100;
    for (double eta : {0.8, 1.0, 1.33, 2.0})
        for (double g : {0.0, 0.5}) {
            const DiffusionMedium m = medium(0.9, g, eta);
            const PhotonBeamDiffusion p(m, o);
            for (double r : {0.0, 2.5e-3, 0.1, 1.0, 4.0}) {
                const double ms = pbrt_ms(m.sigma_s, m.sigma_a, g, eta, r, 100);
                const double ss = pbrt_ss(m.sigma_s, m.sigma_a, g, eta, r, 100);
                EXPECT_NEAR(p.rd_multiple(r), ms, 1e-12 * ms) << "eta " << eta << " r " << r;
                EXPECT_NEAR(p.rd_single(r), ss, 1e-12 * ss) << "eta " << eta << " r " << r;
                EXPECT_NEAR(p.rd(r), ms + ss, 1e-12 * (ms + ss));
            }
        }
}

TEST(DiffusionPbd, ConvergedBeamIntegralsMatchAnIndependentQuadrature) {
    // The beam integrals of BeamDiffusionMS/SS by Simpson here: MS over ln z (the integrand
    // scales with r below z ~ r), SS over the depth t from t_crit (zero before) in ln(t - t_crit),
    // where 1 - F ~ sqrt(t - t_crit) becomes smooth. 2e5 intervals over ~25 units of ln: Simpson's
    // error is far below 1e-10; the cut-off below 1e-9 r (MS) and 1e-12 r (SS) leaves < 1e-9 out;
    // the library integrates to 1e-10.
    for (double eta : {0.8, 1.33})
        for (double g : {0.0, -0.5}) {
            const DiffusionMedium m = medium(0.95, g, eta);
            const PhotonBeamDiffusion p(m);
            for (double r : {0.05, 0.5, 2.0}) {
                auto ms_integrand = [&](double x) {
                    const double z = std::exp(x), st = m.sigma_t_reduced();
                    return z * st * std::exp(-st * z) *
                           pbrt_ms_at(m.sigma_s, m.sigma_a, g, eta, r, z);
                };
                const double ms = simpson(ms_integrand, std::log(1e-9 * r), std::log(60.0), 200000);
                EXPECT_NEAR(p.rd_multiple(r), ms, 1e-8 * ms) << "eta " << eta << " r " << r;
                const double t_crit = r * std::sqrt(std::max(0.0, eta * eta - 1));
                auto ss_integrand = [&](double x) {
                    const double t = t_crit + std::exp(x);
                    const double d = std::sqrt(r * r + t * t), mu = t / d;
                    return std::exp(x) * m.sigma_s * std::exp(-(m.sigma_a + m.sigma_s) * (t + d)) /
                           (d * d) * phase_hg(mu, g) * (1 - fresnel(mu, eta)) * mu;
                };
                const double ss =
                    simpson(ss_integrand, std::log(1e-12 * r), std::log(60.0), 200000);
                EXPECT_NEAR(p.rd_single(r), ss, 1e-8 * ss) << "eta " << eta << " r " << r;
            }
        }
}

TEST(DiffusionPbd, SingleScatteringTotalHasItsClosedForm) {
    // Isotropic phase function, index-matched boundary: 2 pi rho int_0^1 (1/4pi) mu/(1 + mu) dmu
    // = (rho/2)(1 - ln 2), the classic single-scattering albedo of a half space.
    for (double albedo : {0.1, 0.5, 0.9, 1.0}) {
        const PhotonBeamDiffusion p(medium(albedo, 0.0, 1.0));
        EXPECT_NEAR(p.total_single(), albedo / 2 * (1 - std::log(2.0)), 1e-13) << albedo;
    }
}

TEST(DiffusionPbd, TermsAndConventions) {
    const DiffusionMedium m = medium(0.9, 0.3, 1.3);
    DiffusionOptions o;
    const PhotonBeamDiffusion both(m, o);
    o.pbd_terms = PbdTerms::multiple;
    const PhotonBeamDiffusion ms(m, o);
    o.pbd_terms = PbdTerms::single;
    const PhotonBeamDiffusion ss(m, o);
    EXPECT_TRUE(both.includes_single_scattering());
    EXPECT_FALSE(ms.includes_single_scattering());
    EXPECT_TRUE(ss.includes_single_scattering());
    EXPECT_DOUBLE_EQ(both.total_rd(), ms.total_rd() + ss.total_rd());
    EXPECT_DOUBLE_EQ(ms.total_rd(), both.total_multiple());
    EXPECT_DOUBLE_EQ(ss.total_rd(), both.total_single());
    for (double r : {0.01, 1.0}) EXPECT_DOUBLE_EQ(both.rd(r), ms.rd(r) + ss.rd(r));
    // Converged: log(1/r) and 1/r at the origin; pbrt's rule is finite there.
    EXPECT_EQ(both.rd(0), kInf);
    o.pbd_terms = PbdTerms::both;
    o.pbd_depth_samples = 100;
    EXPECT_TRUE(std::isfinite(PhotonBeamDiffusion(m, o).rd(0)));
    // MS grows like log(1/r) as r -> 0 (one decade adds a constant), SS like 1/r.
    const double a = ms.rd(1e-6), b = ms.rd(1e-7), c = ms.rd(1e-8);
    EXPECT_NEAR((c - b) / (b - a), 1.0, 1e-3);
    EXPECT_NEAR(ss.rd(1e-8) / ss.rd(1e-7), 10.0, 1e-3);
}

// ---- Normalized diffusion -----------------------------------------------------------------------

TEST(DiffusionBurley, CdfAndScalingAreChristensenBurleys) {
    const DiffusionMedium m = medium(0.9, 0.0, 1.3);  // sigma_t' = 1: l = 1 for the mfp fits
    DiffusionOptions o;
    o.surface_albedo = 0.8;
    const NormalizedDiffusion search(m, BurleyFit::searchlight, o);
    const NormalizedDiffusion diffuse(m, BurleyFit::diffuse, o);
    const NormalizedDiffusion dmfp(m, BurleyFit::dmfp, o);
    EXPECT_NEAR(search.shape_length(), 1 / 1.05, 1e-15);     // s = 1.85 - 0.8 + 0
    EXPECT_NEAR(diffuse.shape_length(), 1 / 1.1, 1e-15);     // s = 1.9 - 0.8 + 0
    const double ld = std::sqrt((2 * 0.1 + 0.9) / 3 / 0.1);  // sqrt(D_G / sigma_a)
    EXPECT_NEAR(dmfp.shape_length(), ld / (3.5 + 100 * std::pow(0.47, 4)), 1e-14);
    for (const NormalizedDiffusion* p : {&search, &diffuse, &dmfp}) {
        EXPECT_EQ(p->total_rd(), 0.8);
        EXPECT_TRUE(p->includes_single_scattering());
        // [CB15 Eq. 11]: 2 pi int_0^r R r dr = A (1 - e^{-r/d}/4 - 3 e^{-r/(3d)}/4).
        const double d = p->shape_length();
        auto cdf = [&](double r) {
            return 0.8 * (1 - std::exp(-r / d) / 4 - 3 * std::exp(-r / (3 * d)) / 4);
        };
        for (auto [r0, r1] : {std::pair{0.0, 0.01}, {0.0, 1.0}, {0.5, 0.6}, {3.0, 10.0}}) {
            const double expected = (cdf(r1) - cdf(r0)) / (kPi * (r1 * r1 - r0 * r0));
            EXPECT_NEAR(p->annulus_mean(r0, r1), expected, 1e-10 * expected) << p->name();
        }
    }
}

TEST(DiffusionBurley, DefaultSurfaceAlbedoIsThePbdTotal) {
    for (double eta : {0.7, 1.3}) {
        const DiffusionMedium m = medium(0.95, 0.2, eta);
        const double pbd = PhotonBeamDiffusion(m).total_rd();
        for (const std::string name : {"burley-searchlight", "burley-diffuse", "burley-dmfp"})
            EXPECT_DOUBLE_EQ(make_diffusion_profile(name, m)->total_rd(), pbd);
    }
    // dmfp without absorption: l_d = inf, so the profile is 0 while the total is the limit A.
    const NormalizedDiffusion p(medium(1.0, 0.0, 1.3), BurleyFit::dmfp);
    EXPECT_EQ(p.rd(1.0), 0.0);
    EXPECT_GT(p.total_rd(), 0.9);
}

// ---- Annulus averages ---------------------------------------------------------------------------

TEST(DiffusionAnnulus, MatchesABruteForceIntegration) {
    // Brute force: Simpson with 4e4 intervals in u, r = r0 + (r1 - r0) u^2 (dr = 2 (r1 - r0) u du),
    // which makes 1/r and log(1/r) behaviour at r0 = 0 smooth (the integrand tends to 0 there).
    std::map<std::string, double> worst;
    for (const std::string& model : diffusion_model_names()) {
        const DiffusionMedium m = medium(0.9, 0.0, 1.3, model == "multipole" ? 2.0 : kInf);
        const auto p = make_diffusion_profile(model, m);
        for (auto [r0, r1] :
             {std::pair{0.0, 0.02}, {0.0, 0.5}, {0.02, 0.04}, {1.0, 1.1}, {5.0, 7.0}}) {
            auto f = [&, r0 = r0, r1 = r1](double u) {
                if (u == 0) return 0.0;
                const double r = r0 + (r1 - r0) * u * u;
                return 2 * kPi * r * p->rd(r) * 2 * (r1 - r0) * u;
            };
            const int n = model == "pbd" ? 4000 : 40000;
            const double brute = simpson(f, 0, 1, n) / (kPi * (r1 * r1 - r0 * r0));
            const double coarse = simpson(f, 0, 1, n / 2) / (kPi * (r1 * r1 - r0 * r0));
            const double mean = p->annulus_mean(r0, r1);
            EXPECT_NEAR(mean, brute, std::abs(brute - coarse) + 1e-10 * brute)
                << model << " [" << r0 << ", " << r1 << "]";
            worst[model] = std::max(worst[model], std::abs(mean - brute) / brute);
        }
    }
    for (const auto& [model, rel] : worst)
        std::printf("  max |annulus_mean - brute force| / brute force  %-20s %.2e\n", model.c_str(),
                    rel);
    EXPECT_THROW(ClassicalDipole(medium(0.5, 0, 1)).annulus_mean(1, 1), std::invalid_argument);
    EXPECT_THROW(ClassicalDipole(medium(0.5, 0, 1)).annulus_mean(-1, 1), std::invalid_argument);
}

// ---- Parameter inversion ------------------------------------------------------------------------

TEST(DiffusionInversion, RoundTripsForEveryModel) {
    // sigma -> (R_dr, l_d) -> sigma' must reproduce sigma to 1e-9 (the root finder works to
    // ~1e-15 in ln(1 - alpha'); the totals are smooth to ~1e-13).
    double worst = 0;
    for (const std::string& model : diffusion_model_names())
        for (double albedo : {0.05, 0.5, 0.95, 0.9999})
            for (double eta : {0.7, 1.3})
                for (double g : {0.0, 0.7}) {
                    if (g != 0 && albedo != 0.5) continue;
                    DiffusionMedium m = medium(albedo, g, eta);
                    m.sigma_a *= 3;  // a length unit other than 1/sigma_t
                    m.sigma_s *= 3;
                    if (model == "multipole") m.thickness = 1.5;
                    const double rdr = make_diffusion_profile(model, m)->total_rd();
                    InversionTarget t;
                    t.total_rd = rdr;
                    t.ld = diffuse_mean_free_path(m, TransportDefinition::classical);
                    t.g = g;
                    t.eta = eta;
                    t.thickness = m.thickness;
                    const DiffusionMedium r = invert_diffusion_parameters(model, t);
                    const double ea = std::abs(r.sigma_a / m.sigma_a - 1);
                    const double es = std::abs(r.sigma_s / m.sigma_s - 1);
                    EXPECT_LT(ea, 1e-9) << model << " albedo " << albedo << " eta " << eta;
                    EXPECT_LT(es, 1e-9) << model << " albedo " << albedo << " eta " << eta;
                    EXPECT_NEAR(make_diffusion_profile(model, r)->total_rd(), rdr, 1e-9 * rdr);
                    EXPECT_NEAR(diffuse_mean_free_path(r, TransportDefinition::classical), t.ld,
                                1e-9 * t.ld);
                    EXPECT_EQ(r.g, g);
                    EXPECT_EQ(r.eta, eta);
                    worst = std::max({worst, ea, es});
                }
    std::printf("  inversion round trip: max relative error in sigma_a, sigma_s %.2e\n", worst);
}

TEST(DiffusionInversion, GrosjeanDefinitionAndBitterlisParametrisation) {
    for (const std::string model : {"better-dipole", "pbd"}) {
        const DiffusionMedium m = medium(0.9, 0.0, 1.3);
        InversionTarget t;
        t.total_rd = make_diffusion_profile(model, m)->total_rd();
        t.ld = diffuse_mean_free_path(m, TransportDefinition::grosjean);
        t.eta = 1.3;
        const DiffusionMedium r =
            invert_diffusion_parameters(model, t, {}, TransportDefinition::grosjean);
        EXPECT_NEAR(r.sigma_a, m.sigma_a, 1e-9 * m.sigma_a) << model;
        EXPECT_NEAR(r.sigma_s, m.sigma_s, 1e-9 * m.sigma_s) << model;
    }
    // [Bitterli13 Eq. 3.3-3.5] for the dipole: R_dr depends on alpha' only, so the inverted
    // sigma_t' = 1 / (l_d sqrt(3 (1 - alpha'))) with alpha' from Eq. 3.2.
    InversionTarget t;
    t.total_rd = 0.5;
    t.ld = 2.0;
    t.eta = 1.3;
    const DiffusionMedium r = invert_diffusion_parameters("dipole", t);
    const double ap = r.reduced_albedo(), st = r.sigma_t_reduced();
    const double fdr = -1.440 / 1.69 + 0.710 / 1.3 + 0.668 + 0.0636 * 1.3;
    const double a = (1 + fdr) / (1 - fdr), x = std::sqrt(3 * (1 - ap));
    EXPECT_NEAR(ap / 2 * (1 + std::exp(-4.0 / 3.0 * a * x)) * std::exp(-x), 0.5, 1e-12);
    EXPECT_NEAR(st, 1 / (2.0 * x), 1e-12 * st);
}

TEST(DiffusionInversion, ReportsUnattainableAndAmbiguousTargets) {
    InversionTarget t;
    t.ld = 1;
    t.eta = 1.3;
    t.total_rd = 1.2;  // the dipole's R_dr < 1
    EXPECT_THROW(invert_diffusion_parameters("dipole", t), std::invalid_argument);
    t.total_rd = -0.1;
    EXPECT_THROW(invert_diffusion_parameters("qd", t), std::invalid_argument);
    t.total_rd = 0.5;
    t.ld = 0;
    EXPECT_THROW(invert_diffusion_parameters("dipole", t), std::invalid_argument);
    t.ld = 1;
    DiffusionOptions fixed;
    fixed.surface_albedo = 0.5;  // R_dr does not depend on alpha': no unique inverse
    EXPECT_THROW(invert_diffusion_parameters("burley-searchlight", t, fixed), std::domain_error);
    try {
        invert_diffusion_parameters("dipole", [] {
            InversionTarget u;
            u.total_rd = 2;
            return u;
        }());
        ADD_FAILURE() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("outside the range"), std::string::npos);
    }
}

// ---- Stability ----------------------------------------------------------------------------------

TEST(DiffusionStability, FiniteAndNonNegativeOverTheWholeRange) {
    // r = 0 is +inf exactly where the header documents a divergence (pbd: 1/r and log(1/r),
    // burley: 1/r), everything else finite and >= 0.
    const std::vector<double> albedos = {0.0, 1e-6, 0.5, 0.99, 1 - 1e-9, 1.0};
    int evaluations = 0;
    for (const std::string& model : diffusion_model_names())
        for (double albedo : albedos)
            for (double g : {-0.999, 0.0, 0.999})
                for (double eta : {0.7, 1.0, 1.3, 2.5})
                    for (double thickness : {kInf, 3.0}) {
                        if (model != "multipole" && thickness != kInf) continue;
                        DiffusionMedium m = medium(albedo, g, eta);
                        const double mfp = 1 / m.sigma_t_reduced();
                        m.thickness = thickness * mfp;
                        const auto p = make_diffusion_profile(model, m);
                        const std::string what = model + " albedo " + std::to_string(albedo) +
                                                 " g " + std::to_string(g) + " eta " +
                                                 std::to_string(eta);
                        EXPECT_TRUE(std::isfinite(p->total_rd()) && p->total_rd() >= 0) << what;
                        const bool diverges = model == "pbd" || model.rfind("burley", 0) == 0;
                        for (double r : {0.0, 1e-300, 1e-12, 1e-3, 1.0, 1e3, 1e6}) {
                            const double v = p->rd(r * mfp);
                            ++evaluations;
                            EXPECT_GE(v, 0.0) << what << " r " << r;
                            if (r == 0 && diverges && p->total_rd() > 0 &&
                                !(model == "burley-dmfp" && albedo == 1.0))
                                EXPECT_EQ(v, kInf) << what;
                            else
                                EXPECT_TRUE(std::isfinite(v)) << what << " r " << r;
                        }
                        const double first = p->annulus_mean(0, 0.1 * mfp);
                        EXPECT_TRUE(std::isfinite(first) && first >= 0) << what;
                        if (auto* mp = dynamic_cast<const Multipole*>(p.get())) {
                            for (double r : {0.0, 1e-300, 1.0, 1e6}) {
                                const double v = mp->td(r * mfp);
                                EXPECT_TRUE(std::isfinite(v) && v >= 0) << what;
                            }
                        }
                    }
    EXPECT_GT(evaluations, 3000);
}

// ---- Factory, flags, validation -----------------------------------------------------------------

TEST(DiffusionFactory, NamesFlagsAndErrors) {
    const std::vector<std::string> expected = {
        "dipole", "better-dipole",      "multipole",      "qd",
        "pbd",    "burley-searchlight", "burley-diffuse", "burley-dmfp"};
    EXPECT_EQ(diffusion_model_names(), expected);
    const DiffusionMedium m = medium(0.9, 0.0, 1.3);
    for (const std::string& name : expected) {
        const auto p = make_diffusion_profile(name, m);
        EXPECT_EQ(p->name(), name);
        EXPECT_FALSE(p->includes_entry_fresnel()) << name;
        const bool ss = name == "pbd" || name.rfind("burley", 0) == 0;
        EXPECT_EQ(p->includes_single_scattering(), ss) << name;
    }
    try {
        make_diffusion_profile("dipol", m);
        ADD_FAILURE() << "no exception";
    } catch (const std::invalid_argument& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("'dipol'"), std::string::npos) << what;
        for (const std::string& name : expected)
            EXPECT_NE(what.find(name), std::string::npos) << what;
    }
}

TEST(DiffusionFactory, RejectsInvalidMediaAndOptions) {
    auto bad = [](DiffusionMedium m, DiffusionOptions o = {}) {
        EXPECT_THROW(make_diffusion_profile("dipole", m, o), std::invalid_argument);
    };
    bad(DiffusionMedium{-1, 1, 0, 1.3});
    bad(DiffusionMedium{0, 0, 0, 1.3});
    bad(DiffusionMedium{1, 1, 1.0, 1.3});
    bad(DiffusionMedium{1, 1, 0, std::nan("")});
    bad(DiffusionMedium{1, 1, 0, 3.0});  // beyond the fits
    bad(DiffusionMedium{1, 1, 0, 1.3, 0.0});
    DiffusionOptions exact;
    exact.fresnel = FresnelMoments::exact;
    EXPECT_NO_THROW(make_diffusion_profile("dipole", DiffusionMedium{1, 1, 0, 3.0}, exact));
    DiffusionOptions o;
    o.qd_ratio = 1.0;
    EXPECT_THROW(make_diffusion_profile("qd", medium(0.5, 0, 1.3), o), std::invalid_argument);
    o = {};
    o.surface_albedo = 1.5;
    EXPECT_THROW(make_diffusion_profile("burley-dmfp", medium(0.5, 0, 1.3), o),
                 std::invalid_argument);
    o = {};
    o.pbd_depth_samples = -1;
    EXPECT_THROW(make_diffusion_profile("pbd", medium(0.5, 0, 1.3), o), std::invalid_argument);
    const auto p = make_diffusion_profile("qd", medium(0.5, 0, 1.3));
    EXPECT_THROW(p->rd(-1), std::invalid_argument);
    EXPECT_THROW(p->rd(std::nan("")), std::invalid_argument);
    EXPECT_EQ(p->rd(kInf), 0.0);
}

// ---- Numerical building blocks ------------------------------------------------------------------

TEST(DiffusionNumerics, GaussKronrodAndErfcx) {
    // The 15-point Kronrod rule integrates polynomials of degree <= 22 exactly; its embedded
    // 7-point Gauss rule those of degree <= 13 (a mistyped node or weight breaks either).
    for (int k = 0; k <= 22; ++k) {
        auto f = [k](double x) { return std::pow(x, k); };
        const diffusion_detail::Panel p = diffusion_detail::gauss_kronrod15(f, -1.0, 1.0);
        const double exact = k % 2 ? 0.0 : 2.0 / (k + 1);
        EXPECT_NEAR(p.value, exact, 1e-15) << k;
        if (k <= 13) {
            EXPECT_NEAR(p.error, 0.0, 1e-15) << k;
        }
    }
    // erfcx against long double exp(x^2) erfc(x) where that is accurate, both sides of the
    // switch at x = 2, and its asymptote 1/(x sqrt(pi)) far out.
    for (double x : {0.0, 0.3, 1.0, 1.999, 2.0, 2.001, 5.0, 20.0}) {
        const long double ref =
            std::exp(static_cast<long double>(x) * x) * std::erfc(static_cast<long double>(x));
        EXPECT_NEAR(diffusion_detail::erfcx(x), static_cast<double>(ref), 3e-15 * ref) << x;
        EXPECT_NEAR(diffusion_detail::one_minus_sqrtpi_x_erfcx(x),
                    static_cast<double>(1 - std::sqrt(kPi) * x * ref), 1e-14)
            << x;
    }
    const double big = 1e8;
    EXPECT_NEAR(diffusion_detail::erfcx(big) * big * std::sqrt(kPi), 1.0, 1e-15);
    EXPECT_NEAR(diffusion_detail::one_minus_sqrtpi_x_erfcx(big) * 2 * big * big, 1.0, 1e-14);
}

}  // namespace
}  // namespace ssslab::approx
