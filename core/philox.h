// Philox4x32-10 (Salmon, Moraes, Dror & Shaw, "Parallel random numbers: as easy as 1, 2, 3",
// SC'11), sixteen blocks at a time. Bit-identical to Random123's philox4x32
// (tests/test_rng_kernels.cpp checks every path against Random123): the AVX-512 path runs the
// sixteen blocks in the lanes of 512-bit registers, the AVX2 path eight at a time in 256-bit
// lanes, the portable path calls Random123 block by block; which one runs depends only on the
// CPU, never the numbers. (Sixteen rather than eight: the MCML port spent 12 % of its time here;
// with AVX-512 it runs 12-16 % faster in all, the same stream.)
#pragma once

#include <cstdint>

namespace ssslab {

/// Number of blocks per call.
inline constexpr unsigned kPhiloxGroup = 16;

/// Compute Philox4x32-10 of the counters (c0 + i, c1, c2, c3), i = 0..15, under key (k0, k1).
/// Block i = (x0, x1, x2, x3) goes to out[2 i] = x0 * 2^32 + x1 and out[2 i + 1] =
/// x2 * 2^32 + x3. Uses AVX-512 or AVX2 when the CPU has it.
void philox4x32_10_group(std::uint32_t k0, std::uint32_t k1, std::uint32_t c0, std::uint32_t c1,
                         std::uint32_t c2, std::uint32_t c3, std::uint64_t out[2 * kPhiloxGroup]);

/// The same through Random123, one block at a time (the reference; used when AVX2 is absent).
void philox4x32_10_group_portable(std::uint32_t k0, std::uint32_t k1, std::uint32_t c0,
                                  std::uint32_t c1, std::uint32_t c2, std::uint32_t c3,
                                  std::uint64_t out[2 * kPhiloxGroup]);

/// The implementations of philox4x32_10_group(), fastest last.
enum class PhiloxPath { kPortable, kAvx2, kAvx512 };
const char* to_string(PhiloxPath p);
/// The path philox4x32_10_group() takes on this CPU (the fastest it has).
PhiloxPath philox_path();
/// Whether this CPU can run `p`.
bool philox_path_available(PhiloxPath p);
/// philox4x32_10_group() on a given path (for the tests and the micro-benchmark); throws
/// std::invalid_argument if the CPU cannot run it.
void philox4x32_10_group_on(PhiloxPath p, std::uint32_t k0, std::uint32_t k1, std::uint32_t c0,
                            std::uint32_t c1, std::uint32_t c2, std::uint32_t c3,
                            std::uint64_t out[2 * kPhiloxGroup]);

}  // namespace ssslab
