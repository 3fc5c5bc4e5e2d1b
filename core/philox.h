// Philox4x32-10 (Salmon, Moraes, Dror & Shaw, "Parallel random numbers: as easy as 1, 2, 3",
// SC'11), eight blocks at a time. Bit-identical to Random123's philox4x32 (tests/test_sampling.cpp
// checks it against Random123): the AVX2 path runs the eight blocks in the lanes of 256-bit
// registers, the portable path calls Random123 block by block; which one runs depends only on the
// CPU, never the numbers.
#pragma once

#include <cstdint>

namespace ssslab {

/// Number of blocks per call.
inline constexpr unsigned kPhiloxGroup = 8;

/// Compute Philox4x32-10 of the counters (c0 + i, c1, c2, c3), i = 0..7, under key (k0, k1).
/// Block i = (x0, x1, x2, x3) goes to out[2 i] = x0 * 2^32 + x1 and out[2 i + 1] =
/// x2 * 2^32 + x3. Uses AVX2 when the CPU has it.
void philox4x32_10_group(std::uint32_t k0, std::uint32_t k1, std::uint32_t c0, std::uint32_t c1,
                         std::uint32_t c2, std::uint32_t c3, std::uint64_t out[16]);

/// The same through Random123, one block at a time (the reference; used when AVX2 is absent).
void philox4x32_10_group_portable(std::uint32_t k0, std::uint32_t k1, std::uint32_t c0,
                                  std::uint32_t c1, std::uint32_t c2, std::uint32_t c3,
                                  std::uint64_t out[16]);

/// Whether philox4x32_10_group() runs the AVX2 path on this CPU.
bool philox_uses_avx2();

}  // namespace ssslab
