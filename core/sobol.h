// Randomized quasi-Monte Carlo: the first two Sobol dimensions, Owen-scrambled and shuffled by
// hashing [Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)], as pbrt-v4's
// ZSobolSampler and Cycles do, for the first dimensions of a path (the pixel position, the first
// light and scattering decisions).
//
// Why it stays unbiased and its batch statistics honest: for a uniformly random seed, the
// nested uniform scramble maps any fixed 32-bit value to a uniformly distributed one (the hash
// is (x + seed) followed by bijections in which bit j depends only on bits below it, applied to
// the bit-reversed value), so every coordinate of every point is U(0, 1); and points of
// different seeds are independent. An engine that seeds each batch's points from the batch's
// own stream therefore keeps its batches i.i.d., and the batch means' standard errors valid;
// what the scrambled net buys is a smaller variance of each batch mean.
//
// Within one seed the first 2^m shuffled indices of a pair of dimensions are an aligned block of
// 2^m consecutive Sobol points (the index shuffle changes only the low m bits of k < 2^m), a
// (0, m, 2)-net: every elementary interval of area 2^-m holds one point.
#pragma once

#include "core/hash.h"

#include <array>
#include <cstddef>
#include <cstdint>

namespace ssslab {

namespace sobol_detail {

// The bits of x in reverse order: the bits within each byte swapped in three steps, then the
// bytes by one instruction.
inline std::uint32_t reverse_bits(std::uint32_t x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    return __builtin_bswap32(x);
}

// Burley's variant of the Laine-Karras hash: on the bit-reversed value, bit j of the result
// depends only on bits <= j of the input and on the seed, and for a fixed seed it is a
// bijection.
inline std::uint32_t laine_karras(std::uint32_t x, std::uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

}  // namespace sobol_detail

/// An approximate nested uniform (Owen) scramble of a 32-bit fixed-point value.
inline std::uint32_t owen_scramble(std::uint32_t x, std::uint32_t seed) {
    using namespace sobol_detail;
    return reverse_bits(laine_karras(reverse_bits(x), seed));
}

namespace sobol_detail {

// The second dimension's generator matrix (primitive polynomial x + 1: direction numbers
// v_0 = 2^31, v_{i+1} = v_i ^ (v_i >> 1)) applied a byte at a time: entry 256 k + b is the XOR
// of the direction numbers of the bits set in byte k of the index (b at bits 8k .. 8k + 7).
struct SecondDimension {
    std::array<std::uint32_t, 1024> table{};
    constexpr SecondDimension() {
        std::uint32_t v[32] = {};
        v[0] = 1u << 31;
        for (int i = 1; i < 32; ++i) v[i] = v[i - 1] ^ (v[i - 1] >> 1);
        for (int k = 0; k < 4; ++k)
            for (int b = 0; b < 256; ++b) {
                std::uint32_t y = 0;
                for (int j = 0; j < 8; ++j)
                    if (b & (1 << j)) y ^= v[8 * k + j];
                table[static_cast<std::size_t>(256 * k + b)] = y;
            }
    }
};
inline constexpr SecondDimension kSecondDimension{};

}  // namespace sobol_detail

/// The first two dimensions of the Sobol sequence at `index` as 32-bit fixed-point values: the
/// van der Corput sequence and the dimension of primitive polynomial x + 1 (the product of its
/// generator matrix with the index's bits, four table lookups; sobol_2d_bitwise is the
/// definition, bit by bit).
inline void sobol_2d(std::uint32_t index, std::uint32_t& x, std::uint32_t& y) {
    const auto& t = sobol_detail::kSecondDimension.table;
    x = sobol_detail::reverse_bits(index);
    y = t[index & 0xffu] ^ t[256 + ((index >> 8) & 0xffu)] ^ t[512 + ((index >> 16) & 0xffu)] ^
        t[768 + (index >> 24)];
}

/// sobol_2d by the definition: the direction numbers of the index's set bits XORed one by one
/// (what the tables hold, for the test).
inline void sobol_2d_bitwise(std::uint32_t index, std::uint32_t& x, std::uint32_t& y) {
    x = sobol_detail::reverse_bits(index);
    y = 0;
    std::uint32_t v = 1u << 31;
    for (; index != 0; index >>= 1, v ^= v >> 1)
        if (index & 1u) y ^= v;
}

/// The shuffled, Owen-scrambled 2D Sobol sequence of one seed: the index shuffled by an Owen
/// scramble of `seed`, the two coordinates scrambled by seeds hashed from it. `at(index)` is
/// point `index`, each coordinate (k + 1/2) / 2^32 for a 32-bit k: in the open interval (0, 1).
/// The hashed seeds are made once per sequence, and the first coordinate is the shuffle's
/// Laine-Karras hash itself (the van der Corput sequence reverses the bits that owen_scramble
/// has just reversed): the same values as the definition, scrambled_sobol_2d_reference.
struct ScrambledSobol2D {
    std::uint32_t seed, seed_x, seed_y;
    ScrambledSobol2D() : ScrambledSobol2D(0) {}
    explicit ScrambledSobol2D(std::uint32_t s)
        : seed(s), seed_x(hash32(s ^ 0x9e3779b9u)), seed_y(hash32(s ^ 0x7f4a7c15u)) {}
    void at(std::uint32_t index, double& u, double& v) const {
        using namespace sobol_detail;
        const std::uint32_t lk = laine_karras(reverse_bits(index), seed);
        const std::uint32_t shuffled = reverse_bits(lk);  // owen_scramble(index, seed)
        const auto& t = kSecondDimension.table;
        const std::uint32_t y = t[shuffled & 0xffu] ^ t[256 + ((shuffled >> 8) & 0xffu)] ^
                                t[512 + ((shuffled >> 16) & 0xffu)] ^ t[768 + (shuffled >> 24)];
        // x = reverse_bits(shuffled) = lk; its scramble reverses it back to `shuffled`.
        const std::uint32_t xs = reverse_bits(laine_karras(shuffled, seed_x));
        const std::uint32_t ys = owen_scramble(y, seed_y);
        u = (static_cast<double>(xs) + 0.5) * 0x1p-32;
        v = (static_cast<double>(ys) + 0.5) * 0x1p-32;
    }
};

/// Point `index` of ScrambledSobol2D(seed) by its definition, step by step (for the test that
/// the two agree).
inline void scrambled_sobol_2d_reference(std::uint32_t index, std::uint32_t seed, double& u,
                                         double& v) {
    std::uint32_t x = 0, y = 0;
    sobol_2d_bitwise(owen_scramble(index, seed), x, y);
    x = owen_scramble(x, hash32(seed ^ 0x9e3779b9u));
    y = owen_scramble(y, hash32(seed ^ 0x7f4a7c15u));
    u = (static_cast<double>(x) + 0.5) * 0x1p-32;
    v = (static_cast<double>(y) + 0.5) * 0x1p-32;
}

}  // namespace ssslab
