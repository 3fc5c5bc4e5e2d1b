#include "core/philox.h"

#include <Random123/philox.h>

#include <immintrin.h>

namespace ssslab {

void philox4x32_10_group_portable(std::uint32_t k0, std::uint32_t k1, std::uint32_t c0,
                                  std::uint32_t c1, std::uint32_t c2, std::uint32_t c3,
                                  std::uint64_t out[16]) {
    r123::Philox4x32 gen;
    const r123::Philox4x32::key_type key = {{k0, k1}};
    for (unsigned i = 0; i < kPhiloxGroup; ++i) {
        const r123::Philox4x32::ctr_type ctr = {{c0 + i, c1, c2, c3}};
        const auto r = gen(ctr, key);
        out[2 * i] = (static_cast<std::uint64_t>(r[0]) << 32) | r[1];
        out[2 * i + 1] = (static_cast<std::uint64_t>(r[2]) << 32) | r[3];
    }
}

namespace {

[[gnu::target("avx2")]] inline __m256i s(std::uint32_t v) {
    return _mm256_set1_epi32(static_cast<int>(v));
}

// One 32x32 -> 64-bit multiply per lane, returning the high and low halves (mulhilo32 of
// Random123) for all eight lanes.
[[gnu::target("avx2")]] inline void mulhilo8(__m256i m, __m256i x, __m256i& hi, __m256i& lo) {
    const __m256i even = _mm256_mul_epu32(m, x);                        // lanes 0, 2, 4, 6
    const __m256i odd = _mm256_mul_epu32(m, _mm256_srli_epi64(x, 32));  // lanes 1, 3, 5, 7
    lo = _mm256_blend_epi32(even, _mm256_slli_epi64(odd, 32), 0xAA);
    hi = _mm256_blend_epi32(_mm256_srli_epi64(even, 32), odd, 0xAA);
}

[[gnu::target("avx2")]] void group_avx2(std::uint32_t k0, std::uint32_t k1, std::uint32_t c0,
                                        std::uint32_t c1, std::uint32_t c2, std::uint32_t c3,
                                        std::uint64_t out[16]) {
    __m256i x0 = _mm256_add_epi32(s(c0), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    __m256i x1 = s(c1), x2 = s(c2), x3 = s(c3);
    __m256i key0 = s(k0), key1 = s(k1);
    const __m256i m0 = s(0xD2511F53u), m1 = s(0xCD9E8D57u);  // PHILOX_M4x32_0, _1
    const __m256i w0 = s(0x9E3779B9u), w1 = s(0xBB67AE85u);  // PHILOX_W32_0, _1
    for (int round = 0; round < 10; ++round) {
        if (round > 0) {
            key0 = _mm256_add_epi32(key0, w0);
            key1 = _mm256_add_epi32(key1, w1);
        }
        __m256i hi0, lo0, hi1, lo1;
        mulhilo8(m0, x0, hi0, lo0);
        mulhilo8(m1, x2, hi1, lo1);
        x0 = _mm256_xor_si256(_mm256_xor_si256(hi1, x1), key0);
        x1 = lo1;
        x2 = _mm256_xor_si256(_mm256_xor_si256(hi0, x3), key1);
        x3 = lo0;
    }
    alignas(32) std::uint32_t w[4][8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(w[0]), x0);
    _mm256_store_si256(reinterpret_cast<__m256i*>(w[1]), x1);
    _mm256_store_si256(reinterpret_cast<__m256i*>(w[2]), x2);
    _mm256_store_si256(reinterpret_cast<__m256i*>(w[3]), x3);
    for (unsigned i = 0; i < kPhiloxGroup; ++i) {
        out[2 * i] = (static_cast<std::uint64_t>(w[0][i]) << 32) | w[1][i];
        out[2 * i + 1] = (static_cast<std::uint64_t>(w[2][i]) << 32) | w[3][i];
    }
}

}  // namespace

bool philox_uses_avx2() {
    static const bool avx2 = __builtin_cpu_supports("avx2");
    return avx2;
}

void philox4x32_10_group(std::uint32_t k0, std::uint32_t k1, std::uint32_t c0, std::uint32_t c1,
                         std::uint32_t c2, std::uint32_t c3, std::uint64_t out[16]) {
    if (philox_uses_avx2())
        group_avx2(k0, k1, c0, c1, c2, c3, out);
    else
        philox4x32_10_group_portable(k0, k1, c0, c1, c2, c3, out);
}

}  // namespace ssslab
