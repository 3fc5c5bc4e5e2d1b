// Statistical tests of the samplers: Henyey-Greenstein deflection (both inverse CDFs), the spin of
// a direction in both transport modes, the exponential ziggurat, sincos_2pi and the random number
// streams.
//
// Monte Carlo checks follow the project rule (as pbrt, Mitsuba and Nori do): fixed seeds, Pearson
// chi-square over cells of at least 5 expected counts (equiprobable under the analytic CDF) or
// z-tests, at significance 0.01 per family of tests with a Sidak correction. Sample counts are
// multiplied by SSSLAB_TEST_SCALE (the slow.* variants).
#include "core/fastmath.h"
#include "core/rng.h"
#include "core/ziggurat.h"
#include "mcml/ran3.h"
#include "mcml/transport.h"
#include "testing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab {
namespace {

constexpr double kAlpha = 0.01;  ///< family-wise significance
constexpr std::uint64_t kSeed = 0x5eed2024;
constexpr double kEps = std::numeric_limits<double>::epsilon();

/// Stream domains of the individual tests (rng_domain::kTest + id).
enum TestId : std::uint32_t {
    kHgId = 1,
    kHgExtremeId,
    kSpinId,
    kZigguratId,
    kSinCosId,
    kRngId,
};

RngStream test_stream(TestId id, std::uint64_t index) {
    return RngStream(kSeed, rng_domain::kTest + id, index);
}

std::int64_t scaled(double n) {
    return static_cast<std::int64_t>(n * testing::test_scale());
}

/// Two-sided critical value of a z-test at significance `alpha`.
double z_critical(double alpha) {
    return testing::normal_quantile(1.0 - 0.5 * alpha);
}

/// Pearson chi-square test of `observed` against `expected` at significance `alpha`; the message
/// gives the statistic and the critical value.
::testing::AssertionResult chi2_passes(const std::vector<double>& observed,
                                       const std::vector<double>& expected, double alpha) {
    int dof = 0;
    const double chi2 = testing::chi2_statistic(observed, expected, dof);
    const double critical = testing::chi2_critical(dof, alpha);
    std::ostringstream msg;
    msg << "chi2 = " << chi2 << ", critical = " << critical << " (dof " << dof << ", alpha "
        << alpha << ")";
    if (dof >= 1 && chi2 < critical) return ::testing::AssertionSuccess() << msg.str();
    return ::testing::AssertionFailure() << msg.str();
}

/// z-test of `value` against `mean` with standard error `se` at significance `alpha`.
::testing::AssertionResult z_passes(double value, double mean, double se, double alpha) {
    const double z = (value - mean) / se;
    const double critical = z_critical(alpha);
    std::ostringstream msg;
    msg << "value = " << value << ", expected " << mean << " +- " << se
        << ": |z| = " << std::fabs(z) << ", critical = " << critical << " (alpha " << alpha << ")";
    if (std::fabs(z) < critical) return ::testing::AssertionSuccess() << msg.str();
    return ::testing::AssertionFailure() << msg.str();
}

// ---- Henyey-Greenstein ----------------------------------------------------------------------

/// CDF of the HG deflection cosine mu in [-1, 1].
double hg_cdf(double g, double mu) {
    if (g == 0.0) return 0.5 * (mu + 1.0);
    return (1.0 - g * g) / (2.0 * g) *
           (1.0 / std::sqrt(1.0 + g * g - 2.0 * g * mu) - 1.0 / (1.0 + g));
}

/// Edges of `cells` cells of [-1, 1] equiprobable under HG(g), by bisection on hg_cdf (not by
/// the inverse CDF under test).
std::vector<double> hg_cell_edges(double g, int cells) {
    std::vector<double> edges(static_cast<size_t>(cells) + 1);
    edges.front() = -1.0;
    edges.back() = 1.0;
    for (int k = 1; k < cells; ++k) {
        const double p = static_cast<double>(k) / cells;
        double lo = -1.0, hi = 1.0;
        for (int it = 0; it < 200 && hi - lo > 0; ++it) {
            const double mid = 0.5 * (lo + hi);
            if (mid == lo || mid == hi) break;
            if (hg_cdf(g, mid) < p)
                lo = mid;
            else
                hi = mid;
        }
        edges[static_cast<size_t>(k)] = 0.5 * (lo + hi);
    }
    return edges;
}

/// Cell of x among the cells delimited by `edges` (values outside go to the end cells).
size_t cell_of(const std::vector<double>& edges, double x) {
    const auto it = std::upper_bound(edges.begin() + 1, edges.end() - 1, x);
    return static_cast<size_t>(it - (edges.begin() + 1));
}

constexpr int kHgFamily = 8;  // 4 values of g, 2 inverse CDFs
constexpr double kHgG[] = {-0.9, 0.0, 0.5, 0.99};

template <class Sampler>
void check_hg_chi2(Sampler sample, std::uint64_t index0, const char* name) {
    constexpr int kCells = 100;
    const std::int64_t n = scaled(1e6);
    const double alpha = testing::sidak(kAlpha, kHgFamily);
    std::uint64_t index = index0;
    for (const double g : kHgG) {
        SCOPED_TRACE(std::string(name) + ", g = " + std::to_string(g));
        const std::vector<double> edges = hg_cell_edges(g, kCells);
        ASSERT_TRUE(std::is_sorted(edges.begin(), edges.end()));
        ASSERT_TRUE(std::adjacent_find(edges.begin(), edges.end()) == edges.end());
        RngStream rng = test_stream(kHgId, index++);
        std::vector<double> observed(kCells, 0.0);
        std::int64_t bad = 0;
        for (std::int64_t i = 0; i < n; ++i) {
            const double mu = sample(g, rng.uniform());
            if (!(mu >= -1.0 && mu <= 1.0)) ++bad;  // NaN counts as bad
            observed[cell_of(edges, mu)] += 1;
        }
        EXPECT_EQ(bad, 0);
        const std::vector<double> expected(kCells, static_cast<double>(n) / kCells);
        EXPECT_TRUE(chi2_passes(observed, expected, alpha));
    }
}

TEST(HenyeyGreenstein, StableInverseCdfMatchesDistribution) {
    check_hg_chi2(mcml::sample_hg_cos, 0, "sample_hg_cos");
}

TEST(HenyeyGreenstein, McmlInverseCdfMatchesDistribution) {
    check_hg_chi2(mcml::sample_hg_cos_mcml, 100, "sample_hg_cos_mcml");
}

/// Uniforms in (0, 1) for the deterministic checks: the smallest value of RngStream::uniform(),
/// the largest double below 1, extreme doubles, and stream values.
std::vector<double> test_uniforms(std::uint64_t index, std::int64_t n) {
    std::vector<double> u = {0x1p-54,
                             1.0 - 0x1p-53,
                             std::numeric_limits<double>::denorm_min(),
                             std::numeric_limits<double>::min(),
                             1e-300,
                             1e-17,
                             1e-9,
                             0.25,
                             0.5,
                             0.75,
                             0.5 - 0x1p-54,
                             0.5 + 0x1p-53};
    RngStream rng = test_stream(kHgExtremeId, index);
    for (std::int64_t i = 0; i < n; ++i) u.push_back(rng.uniform());
    return u;
}

TEST(HenyeyGreenstein, ExtremeAnisotropyGivesFiniteCosinesInRange) {
    const std::vector<double> us = test_uniforms(0, 100000);
    for (const double g : {-0.999999, 0.999999, 1.0, -1.0}) {
        SCOPED_TRACE("g = " + std::to_string(g));
        for (const double u : us) {
            const double a = mcml::sample_hg_cos(g, u);
            const double b = mcml::sample_hg_cos_mcml(g, u);
            ASSERT_TRUE(std::isfinite(a) && a >= -1.0 && a <= 1.0) << "u = " << u << ": " << a;
            ASSERT_TRUE(std::isfinite(b) && b >= -1.0 && b <= 1.0) << "u = " << u << ": " << b;
            if (std::fabs(g) == 1.0) {  // a delta at mu = g
                ASSERT_EQ(a, g) << "u = " << u;
                ASSERT_EQ(b, g) << "u = " << u;
            }
        }
    }
}

// For tiny |g| the inverse CDF is mu = s + 3/2 g (1 - s^2) + O(g^2) with s = 2u - 1. The stable
// form keeps it to rounding (its bound is O(eps / (1 - |g|)^2)); MCML's formula divides a
// difference of two numbers close to 1 by 2g and loses about log10(1/g) digits.
TEST(HenyeyGreenstein, TinyAnisotropyIsAccurateInTheStableForm) {
    const double g = 1e-9;
    const std::vector<double> us = test_uniforms(1, 100000);
    double stable_err = 0, mcml_err = 0, max_offset = 0;
    for (const double u : us) {
        const long double s = 2.0L * static_cast<long double>(u) - 1.0L;
        const long double ref = s + 1.5L * g * (1.0L - s * s);  // O(g^2) = 1e-18 dropped
        const double a = mcml::sample_hg_cos(g, u);
        ASSERT_TRUE(a >= -1.0 && a <= 1.0) << "u = " << u << ": " << a;
        stable_err = std::max(stable_err, static_cast<double>(std::fabs(a - ref)));
        mcml_err = std::max(mcml_err,
                            static_cast<double>(std::fabs(mcml::sample_hg_cos_mcml(g, u) - ref)));
        max_offset = std::max(max_offset, static_cast<double>(std::fabs(ref - s)));
    }
    // The HG correction is resolved: it is far above the error (about 1.5e-9 at s = 0).
    EXPECT_GT(max_offset, 1e-9);
    EXPECT_LE(stable_err, 4 * kEps);
    EXPECT_GT(mcml_err, 1000 * std::max(stable_err, kEps))
        << "stable error " << stable_err << ", MCML formula error " << mcml_err;
}

// ---- spin_direction --------------------------------------------------------------------------

struct Vec3 {
    double x, y, z;
};

double dot(const Vec3& a, const Vec3& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
Vec3 normalized(const Vec3& a) {
    const double n = std::sqrt(dot(a, a));
    return {a.x / n, a.y / n, a.z / n};
}

/// Incoming directions: the two normal-incidence directions, an oblique one and one with |uz|
/// just below kCosZero (the general rotation with sqrt(1 - uz^2) of about 1.4e-6).
const Vec3 kDirections[] = {
    {0.0, 0.0, 1.0},
    {0.0, 0.0, -1.0},
    normalized({0.3, -0.5, 0.81}),
    normalized({1.2e-6, 0.8e-6, -1.0}),
};
constexpr double kSpinG[] = {0.0, 0.75, -0.5};
constexpr int kSpinCases = 2 * 4 * 3;        // modes x directions x g
constexpr int kSpinFamily = 2 * kSpinCases;  // deflection and azimuth chi-square each

template <bool kCompat, class Rng>
void check_spin(Rng& rng, const Vec3& d, double g) {
    constexpr int kCosCells = 100, kPhiCells = 36;
    const std::int64_t n = scaled(2e5);
    const double alpha = testing::sidak(kAlpha, kSpinFamily);
    ASSERT_NEAR(dot(d, d), 1.0, 4 * kEps);
    // Either normal incidence or the general rotation (not between the two branches).
    ASSERT_TRUE(std::fabs(d.z) == 1.0 || std::fabs(d.z) <= mcml::kCosZero);
    // Frame (e1, e2, d) around the incoming direction.
    const Vec3 helper = std::fabs(d.z) < 0.9 ? Vec3{0, 0, 1} : Vec3{1, 0, 0};
    const Vec3 e1 = normalized(cross(helper, d));
    const Vec3 e2 = cross(d, e1);
    const std::vector<double> edges = hg_cell_edges(g, kCosCells);
    std::vector<double> obs_cos(kCosCells, 0.0), obs_phi(kPhiCells, 0.0);
    double max_norm_err = 0;
    for (std::int64_t i = 0; i < n; ++i) {
        Vec3 v = d;
        mcml::spin_direction<kCompat>(g, v.x, v.y, v.z, rng);
        max_norm_err = std::max(max_norm_err, std::fabs(std::sqrt(dot(v, v)) - 1.0));
        obs_cos[cell_of(edges, dot(v, d))] += 1;
        const double phi = std::atan2(dot(v, e2), dot(v, e1));  // [-pi, pi]
        const int c = static_cast<int>((phi + mcml::kPi) / (2 * mcml::kPi) * kPhiCells);
        obs_phi[static_cast<size_t>(std::clamp(c, 0, kPhiCells - 1))] += 1;
    }
    if (kCompat && std::fabs(d.z) < 1.0) {
        // MCML computes sin(theta_in) as sqrt(1 - uz^2) and divides by it. Near the axis,
        // 1 - uz^2 is known to only a few digits (a unit vector's uz is rounded to a grid of
        // eps / 2), so the rotated frame is scaled by about (1 - uz^2) / (ux^2 + uy^2) = 1 + delta
        // and the new direction's length is off by up to |delta| / 2 (delta ~ eps elsewhere).
        // Compatibility mode reproduces this by design; the bound is that of the original formula.
        const long double p2 =
            static_cast<long double>(d.x) * d.x + static_cast<long double>(d.y) * d.y;
        const double delta = static_cast<double>((1.0 - d.z * d.z) / p2 - 1.0L);
        EXPECT_LE(max_norm_err, 0.5 * std::fabs(delta) * (1 + std::fabs(delta)) + 1e-12)
            << "delta = " << delta;
    } else {
        // Default mode: a rotation keeps the length of any input that is unit to rounding.
        EXPECT_LE(max_norm_err, 1e-12);
    }
    const std::vector<double> exp_cos(kCosCells, static_cast<double>(n) / kCosCells);
    const std::vector<double> exp_phi(kPhiCells, static_cast<double>(n) / kPhiCells);
    EXPECT_TRUE(chi2_passes(obs_cos, exp_cos, alpha)) << "deflection cosine";
    EXPECT_TRUE(chi2_passes(obs_phi, exp_phi, alpha)) << "azimuth";
}

std::string spin_trace(const Vec3& d, double g) {
    std::ostringstream s;
    s.precision(17);
    s << "direction (" << d.x << ", " << d.y << ", " << d.z << "), g = " << g;
    return s.str();
}

TEST(SpinDirection, DefaultModeKeepsUnitLengthAndHgDeflectionWithUniformAzimuth) {
    int index = 0;
    for (const Vec3& d : kDirections) {
        for (const double g : kSpinG) {
            SCOPED_TRACE(spin_trace(d, g));
            RngStream rng = test_stream(kSpinId, static_cast<std::uint64_t>(index++));
            check_spin<false>(rng, d, g);
        }
    }
}

TEST(SpinDirection, CompatModeKeepsUnitLengthAndHgDeflectionWithUniformAzimuth) {
    int index = 0;
    for (const Vec3& d : kDirections) {
        for (const double g : kSpinG) {
            SCOPED_TRACE(spin_trace(d, g));
            mcml::Ran3 rng(-1000 - index++);  // float-rounded: 0 and 1 can come out
            check_spin<true>(rng, d, g);
        }
    }
}

// ---- ExpZiggurat ------------------------------------------------------------------------------

TEST(ExpZiggurat, SamplesFollowUnitExponentialIncludingTheTail) {
    constexpr int kCells = 100;
    constexpr int kFamily = 5;  // chi-square, tail count, tail mean, mean, variance
    const double alpha = testing::sidak(kAlpha, kFamily);
    const std::int64_t n = scaled(1e6);
    std::vector<double> edges(kCells + 1);
    for (int k = 0; k < kCells; ++k) edges[static_cast<size_t>(k)] = -std::log1p(-k / 100.0);
    edges[kCells] = std::numeric_limits<double>::infinity();
    std::vector<double> observed(kCells, 0.0);
    const double r = ExpZiggurat::kR;
    RngStream rng = test_stream(kZigguratId, 0);
    long double sum = 0, sum2 = 0, tail_excess = 0;
    std::int64_t tail = 0, bad = 0;
    for (std::int64_t i = 0; i < n; ++i) {
        const double x = ExpZiggurat::sample(rng);
        if (!(x >= 0.0 && x < std::numeric_limits<double>::infinity())) ++bad;
        observed[cell_of(edges, x)] += 1;
        sum += x;
        sum2 += static_cast<long double>(x) * x;
        if (x > r) {
            ++tail;
            tail_excess += x - r;
        }
    }
    EXPECT_EQ(bad, 0);
    const std::vector<double> expected(kCells, static_cast<double>(n) / kCells);
    EXPECT_TRUE(chi2_passes(observed, expected, alpha)) << "histogram";

    // Tail beyond R: binomial count with p = exp(-R), and excess over R again Exp(1).
    const double p = std::exp(-r), nd = static_cast<double>(n);
    EXPECT_TRUE(z_passes(static_cast<double>(tail), nd * p, std::sqrt(nd * p * (1 - p)), alpha))
        << "samples beyond R";
    ASSERT_GT(tail, 30);
    const double tail_mean = static_cast<double>(tail_excess / tail);
    EXPECT_TRUE(z_passes(tail_mean, 1.0, 1.0 / std::sqrt(static_cast<double>(tail)), alpha))
        << "mean excess beyond R";

    // Mean 1 (sd 1) and variance 1 (sd of the sample variance sqrt((mu4 - 1) / n), mu4 = 9).
    const double mean = static_cast<double>(sum / n);
    const double var = static_cast<double>((sum2 - sum * sum / n) / (n - 1));
    EXPECT_TRUE(z_passes(mean, 1.0, 1.0 / std::sqrt(nd), alpha)) << "mean";
    EXPECT_TRUE(z_passes(var, 1.0, std::sqrt(8.0 / nd), alpha)) << "variance";
}

TEST(ExpZiggurat, TablesDescribeLayersOfEqualArea) {
    const ExpZiggurat::Tables& t = ExpZiggurat::tables();
    const double v = ExpZiggurat::kV, r = ExpZiggurat::kR;
    EXPECT_EQ(t.x[1], r);
    EXPECT_EQ(t.x[256], 0.0);
    EXPECT_EQ(t.f[256], 1.0);
    for (size_t i = 0; i < 256; ++i) EXPECT_GT(t.x[i], t.x[i + 1]) << "i = " << i;
    for (size_t i = 0; i <= 256; ++i) EXPECT_EQ(t.f[i], std::exp(-t.x[i])) << "i = " << i;
    // Base layer: the box [0, x_0] x [0, f(R)] by construction; it must equal the rectangle
    // [0, R] x [0, f(R)] plus the tail area f(R), i.e. x_0 = R + 1: kV and kR agree.
    EXPECT_NEAR(t.x[0] * t.f[1] / v, 1.0, 1e-9);
    EXPECT_NEAR(std::exp(-r) * (r + 1) / v, 1.0, 1e-9);
    // Layers 1..254 have the area V by the recursion; the top layer (i = 255, up to f = 1 at
    // x_256 = 0) is not forced, so its area checks R and V together.
    for (size_t i = 1; i < 256; ++i)
        EXPECT_NEAR(t.x[i] * (t.f[i + 1] - t.f[i]) / v, 1.0, 1e-9) << "layer " << i;
}

// ---- sincos_2pi ------------------------------------------------------------------------------

TEST(SinCos2Pi, AbsoluteErrorBelow4e16) {
    std::vector<double> us = {0.0, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0};
    // Near the octant boundaries, where the quadrant choice switches (0.125 +- 1e-17 rounds to
    // the neighbouring doubles).
    for (int q = 0; q <= 8; ++q) {
        double lo = q / 8.0, hi = q / 8.0;
        for (int k = 0; k < 1000; ++k) {
            lo = std::nextafter(lo, -1.0);
            hi = std::nextafter(hi, 2.0);
            if (lo >= 0.0) us.push_back(lo);
            if (hi <= 1.0) us.push_back(hi);
        }
        for (const double d : {1e-17, 1e-15, 1e-12, 1e-9, 1e-6}) {
            if (q / 8.0 - d >= 0.0) us.push_back(q / 8.0 - d);
            if (q / 8.0 + d <= 1.0) us.push_back(q / 8.0 + d);
        }
    }
    const std::int64_t n = scaled(5e5);
    for (std::int64_t k = 0; k <= n; ++k) us.push_back(static_cast<double>(k) / n);
    RngStream rng = test_stream(kSinCosId, 0);
    for (std::int64_t k = 0; k < n; ++k) us.push_back(rng.uniform());

    constexpr long double kTwoPi = 6.283185307179586476925286766559005768L;
    double max_err = 0, worst_u = 0;
    for (const double u : us) {
        double s, c;
        sincos_2pi(u, &s, &c);
        const long double a = kTwoPi * static_cast<long double>(u);
        const double err =
            static_cast<double>(std::max(std::fabs(s - std::sin(a)), std::fabs(c - std::cos(a))));
        if (!(err <= max_err)) {
            max_err = err;
            worst_u = u;
        }
    }
    EXPECT_LT(max_err, 4e-16) << "worst at u = " << worst_u << " of " << us.size() << " values";

    // The quarter turns are exact.
    const double quarters[][3] = {
        {0.0, 0, 1}, {0.25, 1, 0}, {0.5, 0, -1}, {0.75, -1, 0}, {1.0, 0, 1}};
    for (const auto& q : quarters) {
        double s, c;
        sincos_2pi(q[0], &s, &c);
        EXPECT_EQ(s, q[1]) << "u = " << q[0];
        EXPECT_EQ(c, q[2]) << "u = " << q[0];
    }
}

// ---- RngStream -------------------------------------------------------------------------------

TEST(RngStream, SequenceIsAFunctionOfSeedDomainAndIndex) {
    RngStream a(kSeed, rng_domain::kTest + kRngId, 7), b(kSeed, rng_domain::kTest + kRngId, 7);
    for (int i = 0; i < 1000; ++i) ASSERT_EQ(a.next_u64(), b.next_u64()) << "word " << i;

    const std::uint64_t first = RngStream(kSeed, rng_domain::kTest + kRngId, 7).next_u64();
    EXPECT_NE(RngStream(kSeed, rng_domain::kTest + kRngId, 8).next_u64(), first);
    EXPECT_NE(RngStream(kSeed, rng_domain::kTest + kRngId + 1, 7).next_u64(), first);
    EXPECT_NE(RngStream(kSeed, rng_domain::kMcml, 7).next_u64(), first);
    EXPECT_NE(RngStream(kSeed + 1, rng_domain::kTest + kRngId, 7).next_u64(), first);
    // Neighbouring indices also differ after the first word (different counters throughout).
    RngStream c(kSeed, rng_domain::kTest + kRngId, 7), d(kSeed, rng_domain::kTest + kRngId, 8);
    int equal = 0;
    for (int i = 0; i < 1000; ++i) equal += c.next_u64() == d.next_u64();
    EXPECT_EQ(equal, 0);
}

TEST(RngStream, WordsDrawnCountsEveryWord) {
    RngStream rng = test_stream(kRngId, 1);
    EXPECT_EQ(rng.words_drawn(), 0u);
    for (std::uint64_t k = 1; k <= 200; ++k) {  // across several refills of the buffer
        if (k % 3 == 0)
            (void)rng.uniform();
        else
            (void)rng.next_u64();
        ASSERT_EQ(rng.words_drawn(), k);
    }
}

TEST(RngStream, UniformIsInTheOpenIntervalUniformAndSeriallyUncorrelated) {
    constexpr int kCells = 100;
    constexpr int kFamily = 2;  // chi-square, serial correlation
    const double alpha = testing::sidak(kAlpha, kFamily);
    const std::int64_t n = scaled(1e6);
    RngStream rng = test_stream(kRngId, 2);
    std::vector<double> observed(kCells, 0.0);
    std::int64_t outside = 0;
    double prev = rng.uniform() - 0.5;
    long double sxy = 0, sxx = 0;
    for (std::int64_t i = 0; i < n; ++i) {
        const double u = rng.uniform();
        if (!(u > 0.0 && u < 1.0)) ++outside;
        observed[static_cast<size_t>(std::min(static_cast<int>(u * kCells), kCells - 1))] += 1;
        const double x = u - 0.5;
        sxy += static_cast<long double>(prev) * x;
        sxx += static_cast<long double>(x) * x;
        prev = x;
    }
    EXPECT_EQ(outside, 0);
    const std::vector<double> expected(kCells, static_cast<double>(n) / kCells);
    EXPECT_TRUE(chi2_passes(observed, expected, alpha));
    // Lag-1 correlation: r sqrt(n) is standard normal for independent draws.
    const double r = static_cast<double>(sxy / sxx);
    EXPECT_TRUE(z_passes(r, 0.0, 1.0 / std::sqrt(static_cast<double>(n)), alpha))
        << "serial correlation";
}

}  // namespace
}  // namespace ssslab
