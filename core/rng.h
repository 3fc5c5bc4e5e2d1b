// Counter-based random number streams.
//
// Every Monte Carlo engine in ssslab draws its random numbers from streams keyed by
// (seed, domain, index): the seed is the user's, the domain separates independent uses (an RGB
// channel, an engine, a test), and the index is the batch number. Work is split into fixed
// batches, each with its own stream, so results do not depend on how batches are spread over
// threads or processes, and an interrupted run can resume at any batch (docs/architecture.md,
// "Determinism").
//
// The generator is Philox4x32-10 (Salmon et al., SC'11; Random123's philox4x32): it passes
// BigCrush with a margin of several rounds. Blocks are computed eight at a time (core/philox.h),
// with AVX2 where the CPU has it: 1.2 ns per double against 3.4 ns for Random123's
// Philox4x64-10 one block at a time, on this project's machine class.
#pragma once

#include "core/philox.h"

#include <array>
#include <cstdint>
#include <stdexcept>

namespace ssslab {

/// A sequential stream of uniform random numbers: Philox4x32-10 under the key (seed low 32 bits,
/// seed high 32 bits) at the counters (block mod 2^32, block / 2^32 + domain * 2^16, index low,
/// index high) for block = 0, 1, 2, ... Each block gives two 64-bit words.
class RngStream {
  public:
    /// `domain` must be below 2^16 (see rng_domain); `index` is any 64-bit batch number.
    RngStream(std::uint64_t seed, std::uint32_t domain, std::uint64_t index)
        : k0_(static_cast<std::uint32_t>(seed)),
          k1_(static_cast<std::uint32_t>(seed >> 32)),
          c2_(static_cast<std::uint32_t>(index)),
          c3_(static_cast<std::uint32_t>(index >> 32)),
          domain_(domain) {
        if (domain >= (1u << 16)) throw std::invalid_argument("RngStream: domain >= 2^16");
    }

    /// Next 64 random bits.
    std::uint64_t next_u64() {
        if (pos_ == kWords) refill();
        return buf_[pos_++];
    }

    /// Uniform double in the open interval (0, 1): (2k + 1) / 2^53 for a 52-bit k, exact in a
    /// double, so neither 0 (log(0) in free-path sampling) nor 1 (0/0 in HG sampling with
    /// g = -1) can come out. (Adding 1/2 to a 53-bit k would round to 1 for k = 2^53 - 1.)
    double uniform() {
        if (prefix_left_ > 0) [[unlikely]] {
            --prefix_left_;
            return *prefix_++;
        }
        return stream_uniform();
    }

    /// uniform() from the stream itself, past a prefix (which stays for the next uniform()
    /// calls): for a choice that is not to take one of the quasi-random dimensions.
    double stream_uniform() {
        // The value fits a signed 64-bit integer: one cvtsi2sd instead of the slow unsigned
        // 64-bit conversion.
        return static_cast<double>(static_cast<std::int64_t>((next_u64() >> 11) | 1)) * 0x1p-53;
    }

    /// A quasi-random prefix: the next `n` calls of uniform() return values[0], ..., values[n-1]
    /// (each in the open interval (0, 1), e.g. core/sobol.h's scrambled points for the first
    /// dimensions of one path), then the stream continues where it was; the stream's own
    /// numbers are not consumed meanwhile. The caller keeps `values` alive; n = 0 ends a prefix
    /// early.
    void set_prefix(const double* values, unsigned n) {
        prefix_ = values;
        prefix_left_ = n;
    }

    /// Number of 64-bit words drawn so far (for tests and call-order checks).
    std::uint64_t words_drawn() const { return groups_ * kWords - (kWords - pos_); }

  private:
    static constexpr unsigned kWords = 2 * kPhiloxGroup;  // 64-bit words per group of blocks

    [[gnu::noinline]] void refill() {
        const std::uint64_t block = groups_ * kPhiloxGroup;
        if ((block >> 48) != 0) throw std::overflow_error("RngStream: 2^48 blocks exhausted");
        philox4x32_10_group(k0_, k1_, static_cast<std::uint32_t>(block),
                            static_cast<std::uint32_t>(block >> 32) | (domain_ << 16), c2_, c3_,
                            buf_.data());
        ++groups_;
        pos_ = 0;
    }

    std::uint32_t k0_, k1_, c2_, c3_, domain_;
    std::uint64_t groups_ = 0;
    std::array<std::uint64_t, kWords> buf_{};
    unsigned pos_ = kWords;
    const double* prefix_ = nullptr;
    unsigned prefix_left_ = 0;
};

/// Fixed stream domains (16 bits), so that two uses of the same seed never share a stream.
namespace rng_domain {
inline constexpr std::uint32_t kMcml = 0x1000;     ///< + run index or RGB channel (< 0x8000)
inline constexpr std::uint32_t kTest = 0x9000;     ///< + test id
inline constexpr std::uint32_t kVolpath = 0xA000;  ///< + run index (< 0x1000)
inline constexpr std::uint32_t kScene = 0xB000;    ///< procedural scene geometry (+ shape index)
inline constexpr std::uint32_t kSssReference = 0xC000;  ///< realtime/sss_reference.h's sampling
inline constexpr std::uint32_t kPointCloud = 0xD000;    ///< approx/hierarchical.h's surface points
}  // namespace rng_domain

}  // namespace ssslab
