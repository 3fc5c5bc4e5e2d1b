// Exact sampling of the unit exponential distribution by the ziggurat method, without a log on
// the fast path [Marsaglia & Tsang 2000, "The Ziggurat Method for Generating Random Variables";
// 256 layers with the table layout of Doornik 2005]. Free-path sampling s = -ln(u) / mu_t took a
// tenth of the MCML engine's time in glibc's log().
//
// Layer i (0 <= i < 256) is the box [0, x_i] x [f(x_i), f(x_{i+1})] with f(x) = exp(-x); all have
// the area V, the base layer includes the tail beyond R = x_1. A draw picks a layer from 8 random
// bits and a point x = u x_i from 53 others; x < x_{i+1} lies under the curve (accepted at once,
// 98.9 % of draws); otherwise the point is accepted if below f, and in the base layer the tail is
// R + Exp(1) by memorylessness. The method is exact: accepted x has density exp(-x).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

namespace ssslab {

class ExpZiggurat {
  public:
    static constexpr double kR = 7.69711747013104972;   ///< start of the tail
    static constexpr double kV = 3.949659822581572e-3;  ///< area of each layer

    /// Draw from Exp(1). `Rng` provides next_u64() and uniform() in (0, 1).
    template <class Rng>
    static double sample(Rng& rng) {
        const Tables& t = tables();
        for (;;) {
            const std::uint64_t bits = rng.next_u64();
            const unsigned i = static_cast<unsigned>(bits & 0xff);
            const double u = static_cast<double>(static_cast<std::int64_t>(bits >> 11)) * 0x1p-53;
            const double x = u * t.x[i];
            if (x < t.x[i + 1]) return x;
            if (i == 0) return kR - std::log(rng.uniform());
            if (t.f[i] + (t.f[i + 1] - t.f[i]) * rng.uniform() < std::exp(-x)) return x;
        }
    }

    struct Tables {
        std::array<double, 257> x;  ///< x_0 = V / f(R) > x_1 = R > ... > x_256 = 0
        std::array<double, 257> f;  ///< f(x_i)
    };
    static const Tables& tables() {
        static const Tables t = make_tables();
        return t;
    }

  private:
    static Tables make_tables() {
        Tables t;
        t.x[0] = kV / std::exp(-kR);
        t.x[1] = kR;
        for (int i = 1; i < 255; ++i)
            t.x[static_cast<size_t>(i) + 1] = -std::log(kV / t.x[static_cast<size_t>(i)] +
                                                        std::exp(-t.x[static_cast<size_t>(i)]));
        t.x[256] = 0.0;
        for (size_t i = 0; i < 257; ++i) t.f[i] = std::exp(-t.x[i]);
        return t;
    }
};

}  // namespace ssslab
