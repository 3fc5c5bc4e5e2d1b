// The counter-based generator: the eight-block Philox4x32-10 (AVX2 where available) against
// Random123's own implementation, the counter layout of RngStream, and the 2D Sobol points
// (core/sobol.h).
#include "core/philox.h"
#include "core/rng.h"
#include "core/sobol.h"

#include <Random123/philox.h>
#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace ssslab {
namespace {

TEST(Philox, GroupEqualsRandom123BlockByBlock) {
    std::mt19937_64 pick(42);
    r123::Philox4x32 gen;
    for (int trial = 0; trial < 2000; ++trial) {
        const auto k0 = static_cast<std::uint32_t>(pick()), k1 = static_cast<std::uint32_t>(pick());
        // Include counters at the top of the 32-bit range.
        const std::uint32_t c0 =
            trial % 3 == 0 ? 0xFFFFFFF0u : static_cast<std::uint32_t>(pick()) & ~(kPhiloxGroup - 1);
        const auto c1 = static_cast<std::uint32_t>(pick()), c2 = static_cast<std::uint32_t>(pick()),
                   c3 = static_cast<std::uint32_t>(pick());
        std::uint64_t fast[2 * kPhiloxGroup];
        philox4x32_10_group(k0, k1, c0, c1, c2, c3, fast);
        // Every path this CPU has gives Random123's blocks; the default path is one of them.
        for (PhiloxPath path : {PhiloxPath::kPortable, PhiloxPath::kAvx2, PhiloxPath::kAvx512}) {
            if (!philox_path_available(path)) continue;
            std::uint64_t out[2 * kPhiloxGroup];
            philox4x32_10_group_on(path, k0, k1, c0, c1, c2, c3, out);
            for (unsigned i = 0; i < kPhiloxGroup; ++i) {
                const auto r = gen({{c0 + i, c1, c2, c3}}, {{k0, k1}});
                const std::uint64_t w0 = (std::uint64_t(r[0]) << 32) | r[1];
                const std::uint64_t w1 = (std::uint64_t(r[2]) << 32) | r[3];
                ASSERT_EQ(out[2 * i], w0)
                    << to_string(path) << " trial " << trial << " block " << i;
                ASSERT_EQ(out[2 * i + 1], w1) << to_string(path);
                if (path == philox_path()) {
                    ASSERT_EQ(fast[2 * i], w0);
                }
            }
        }
    }
    RecordProperty("path", to_string(philox_path()));
}

TEST(Philox, KnownAnswerOfRandom123) {
    // Random123's kat_vectors: philox4x32 10 rounds, counter and key zero.
    r123::Philox4x32 gen;
    const auto r = gen({{0, 0, 0, 0}}, {{0, 0}});
    EXPECT_EQ(r[0], 0x6627e8d5u);
    EXPECT_EQ(r[1], 0xe169c58du);
    EXPECT_EQ(r[2], 0xbc57ac4cu);
    EXPECT_EQ(r[3], 0x9b00dbd8u);
    std::uint64_t out[2 * kPhiloxGroup];
    philox4x32_10_group(0, 0, 0, 0, 0, 0, out);
    EXPECT_EQ(out[0], 0x6627e8d5e169c58dull);
    EXPECT_EQ(out[1], 0xbc57ac4c9b00dbd8ull);
}

TEST(RngStream, CounterLayoutIsSeedDomainIndex) {
    const std::uint64_t seed = 0x0123456789abcdefull, index = 0xfedcba9876543210ull;
    const std::uint32_t domain = rng_domain::kMcml + 2;
    RngStream s(seed, domain, index);
    r123::Philox4x32 gen;
    for (std::uint32_t block = 0; block < 20; ++block) {
        const auto r =
            gen({{block, domain << 16, 0x76543210u, 0xfedcba98u}}, {{0x89abcdefu, 0x01234567u}});
        EXPECT_EQ(s.next_u64(), (std::uint64_t(r[0]) << 32) | r[1]) << block;
        EXPECT_EQ(s.next_u64(), (std::uint64_t(r[2]) << 32) | r[3]) << block;
    }
    EXPECT_EQ(s.words_drawn(), 40u);
    EXPECT_THROW(RngStream(1, 1u << 16, 0), std::invalid_argument);
}

}  // namespace
}  // namespace ssslab

namespace ssslab {
namespace {

TEST(Sobol, TablesEqualTheDefinitionAndTheFirstPointsFormNets) {
    // The table lookups against the bit-by-bit definition, on every 16-bit index and random
    // 32-bit ones.
    std::mt19937_64 pick(7);
    for (std::uint64_t k = 0; k < (1u << 16) + 200000; ++k) {
        const auto i =
            k < (1u << 16) ? static_cast<std::uint32_t>(k) : static_cast<std::uint32_t>(pick());
        std::uint32_t x = 0, y = 0, xb = 0, yb = 0;
        sobol_2d(i, x, y);
        sobol_2d_bitwise(i, xb, yb);
        ASSERT_EQ(x, xb) << i;
        ASSERT_EQ(y, yb) << i;
    }
    // Independent of both: the first 2^m points of the first two Sobol dimensions form a
    // (0, m, 2)-net in base 2: every elementary interval [a 2^-j, (a + 1) 2^-j) x
    // [b 2^-(m - j), (b + 1) 2^-(m - j)) holds exactly one point.
    for (int m = 1; m <= 12; ++m)
        for (int j = 0; j <= m; ++j) {
            std::vector<int> count(std::size_t{1} << m, 0);
            for (std::uint32_t i = 0; i < (1u << m); ++i) {
                std::uint32_t x = 0, y = 0;
                sobol_2d(i, x, y);
                const std::uint32_t a = j == 0 ? 0 : x >> (32 - j);
                const std::uint32_t b = m - j == 0 ? 0 : y >> (32 - (m - j));
                ++count[(a << (m - j)) | b];
            }
            for (int c : count) ASSERT_EQ(c, 1) << "m " << m << ", j " << j;
        }
}

TEST(Sobol, ScrambledPointsEqualTheDefinitionAndFormNets) {
    // reverse_bits against the bit-by-bit reversal.
    std::mt19937_64 pick(11);
    for (int k = 0; k < 100000; ++k) {
        const auto x = static_cast<std::uint32_t>(pick());
        std::uint32_t r = 0;
        for (int b = 0; b < 32; ++b) r |= ((x >> b) & 1u) << (31 - b);
        ASSERT_EQ(sobol_detail::reverse_bits(x), r) << x;
    }
    // The sequence object (hashed seeds made once, the double reversal left out) against the
    // definition step by step, bit for bit.
    for (int k = 0; k < 200000; ++k) {
        const auto seed = static_cast<std::uint32_t>(pick());
        const auto index = static_cast<std::uint32_t>(k < 100000 ? k : pick());
        double u = 0, v = 0, ur = 0, vr = 0;
        ScrambledSobol2D(seed).at(index, u, v);
        scrambled_sobol_2d_reference(index, seed, ur, vr);
        ASSERT_EQ(u, ur) << seed << " " << index;
        ASSERT_EQ(v, vr) << seed << " " << index;
    }
    // Independent of both: the scrambles keep the net, the first 2^m points of every seed's
    // sequence a (0, m, 2)-net in base 2 [Burley 2020, §3-4].
    for (std::uint32_t seed : {1u, 0x9e3779b9u, 123456789u})
        for (int m = 1; m <= 10; ++m)
            for (int j = 0; j <= m; ++j) {
                std::vector<int> count(std::size_t{1} << m, 0);
                const ScrambledSobol2D seq(seed);
                for (std::uint32_t i = 0; i < (1u << m); ++i) {
                    double u = 0, v = 0;
                    seq.at(i, u, v);
                    const auto a = static_cast<std::uint32_t>(u * (1u << j));
                    const auto b = static_cast<std::uint32_t>(v * (1u << (m - j)));
                    ++count[(a << (m - j)) | b];
                }
                for (int c : count)
                    ASSERT_EQ(c, 1) << "seed " << seed << ", m " << m << ", j " << j;
            }
}

}  // namespace
}  // namespace ssslab
