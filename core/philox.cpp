#include "core/philox.h"

#include <Random123/philox.h>

#include <immintrin.h>

#include <stdexcept>
#include <string>

namespace ssslab {

void philox4x32_10_group_portable(std::uint32_t k0, std::uint32_t k1, std::uint32_t c0,
                                  std::uint32_t c1, std::uint32_t c2, std::uint32_t c3,
                                  std::uint64_t out[2 * kPhiloxGroup]) {
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

// Eight blocks (c0 + i, ...), i = 0..7, into out[0..15].
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
    for (unsigned i = 0; i < 8; ++i) {
        out[2 * i] = (static_cast<std::uint64_t>(w[0][i]) << 32) | w[1][i];
        out[2 * i + 1] = (static_cast<std::uint64_t>(w[2][i]) << 32) | w[3][i];
    }
}

// GCC 12's _mm512_undefined_epi32 (inside mul_epu32 and the shifts) initialises a variable with
// itself, which -Wuninitialized reports at every use (GCC bug 105593, fixed in GCC 13).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
[[gnu::target("avx512f")]] inline __m512i s16(std::uint32_t v) {
    return _mm512_set1_epi32(static_cast<int>(v));
}

[[gnu::target("avx512f")]] inline void mulhilo16(__m512i m, __m512i x, __m512i& hi, __m512i& lo) {
    const __m512i even = _mm512_mul_epu32(m, x);
    const __m512i odd = _mm512_mul_epu32(m, _mm512_srli_epi64(x, 32));
    lo = _mm512_mask_blend_epi32(0xAAAA, even, _mm512_slli_epi64(odd, 32));
    hi = _mm512_mask_blend_epi32(0xAAAA, _mm512_srli_epi64(even, 32), odd);
}

// Sixteen blocks in the lanes of 512-bit registers.
[[gnu::target("avx512f")]] void group_avx512(std::uint32_t k0, std::uint32_t k1, std::uint32_t c0,
                                             std::uint32_t c1, std::uint32_t c2, std::uint32_t c3,
                                             std::uint64_t out[2 * kPhiloxGroup]) {
    __m512i x0 = _mm512_add_epi32(
        s16(c0), _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
    __m512i x1 = s16(c1), x2 = s16(c2), x3 = s16(c3);
    __m512i key0 = s16(k0), key1 = s16(k1);
    const __m512i m0 = s16(0xD2511F53u), m1 = s16(0xCD9E8D57u);
    const __m512i w0 = s16(0x9E3779B9u), w1 = s16(0xBB67AE85u);
    for (int round = 0; round < 10; ++round) {
        if (round > 0) {
            key0 = _mm512_add_epi32(key0, w0);
            key1 = _mm512_add_epi32(key1, w1);
        }
        __m512i hi0, lo0, hi1, lo1;
        mulhilo16(m0, x0, hi0, lo0);
        mulhilo16(m1, x2, hi1, lo1);
        x0 = _mm512_xor_si512(_mm512_xor_si512(hi1, x1), key0);
        x1 = lo1;
        x2 = _mm512_xor_si512(_mm512_xor_si512(hi0, x3), key1);
        x3 = lo0;
    }
    alignas(64) std::uint32_t w[4][16];
    _mm512_store_si512(w[0], x0);
    _mm512_store_si512(w[1], x1);
    _mm512_store_si512(w[2], x2);
    _mm512_store_si512(w[3], x3);
    for (unsigned i = 0; i < 16; ++i) {
        out[2 * i] = (static_cast<std::uint64_t>(w[0][i]) << 32) | w[1][i];
        out[2 * i + 1] = (static_cast<std::uint64_t>(w[2][i]) << 32) | w[3][i];
    }
}

#pragma GCC diagnostic pop

}  // namespace

const char* to_string(PhiloxPath p) {
    switch (p) {
        case PhiloxPath::kAvx512:
            return "AVX-512";
        case PhiloxPath::kAvx2:
            return "AVX2";
        case PhiloxPath::kPortable:
            break;
    }
    return "portable";
}

bool philox_path_available(PhiloxPath p) {
    static const bool avx2 = __builtin_cpu_supports("avx2");
    static const bool avx512 = __builtin_cpu_supports("avx512f");
    return p == PhiloxPath::kPortable || (p == PhiloxPath::kAvx2 && avx2) ||
           (p == PhiloxPath::kAvx512 && avx512);
}

PhiloxPath philox_path() {
    static const PhiloxPath p = philox_path_available(PhiloxPath::kAvx512) ? PhiloxPath::kAvx512
                                : philox_path_available(PhiloxPath::kAvx2) ? PhiloxPath::kAvx2
                                                                           : PhiloxPath::kPortable;
    return p;
}

void philox4x32_10_group_on(PhiloxPath p, std::uint32_t k0, std::uint32_t k1, std::uint32_t c0,
                            std::uint32_t c1, std::uint32_t c2, std::uint32_t c3,
                            std::uint64_t out[2 * kPhiloxGroup]) {
    if (!philox_path_available(p))
        throw std::invalid_argument(std::string("philox: this CPU has no ") + to_string(p));
    switch (p) {
        case PhiloxPath::kAvx512:
            group_avx512(k0, k1, c0, c1, c2, c3, out);
            return;
        case PhiloxPath::kAvx2:
            group_avx2(k0, k1, c0, c1, c2, c3, out);
            group_avx2(k0, k1, c0 + 8, c1, c2, c3, out + 16);
            return;
        case PhiloxPath::kPortable:
            break;
    }
    philox4x32_10_group_portable(k0, k1, c0, c1, c2, c3, out);
}

void philox4x32_10_group(std::uint32_t k0, std::uint32_t k1, std::uint32_t c0, std::uint32_t c1,
                         std::uint32_t c2, std::uint32_t c3, std::uint64_t out[2 * kPhiloxGroup]) {
    philox4x32_10_group_on(philox_path(), k0, k1, c0, c1, c2, c3, out);
}

}  // namespace ssslab
