// What a path expects to collect from a point inside a medium on, learnt from the renderer's
// own paths: the adjoint estimate of adjoint-driven Russian roulette and splitting [Vorba and
// Křivánek 2016, "Adjoint-Driven Russian Roulette and Splitting in Light Transport Simulation"],
// as volume path guiding uses it [Herholz et al. 2019, "Volume Path Guiding Based on
// Zero-Variance Random Walk Theory", §5], here with the second moment in place of the mean
// [Rath et al. 2022, "EARS: Efficiency-Aware Russian Roulette and Splitting", §4: where rare
// large contributions make the noise, the mean misses where they come from]. A path at a
// scattering vertex x with throughput b collects b L from there on, L a random variable of x;
// b sqrt(E[L^2]) against the root second moment of the pixel's samples says whether to end it
// by a roulette or split it (volpath/render.cpp).
//
// Space: a uniform grid of cubic cells over a box (the guided media's bounds), kMaxCells along
// its longest side; per cell the moments of the estimates recorded there (none with fewer than
// kMinRecords). A Tally gathers one share of a learning pass (its own rows of pixels); learning
// from the shares in a fixed order makes what is learnt the same whatever the threads (and a
// render resumed from a checkpoint learns what it started with).
#pragma once

#include "core/vec3.h"

#include <cstdint>
#include <vector>

namespace ssslab::volpath {

class RadianceGrid {
  public:
    static constexpr int kMaxCells = 64;
    static constexpr std::int64_t kMinRecords = 16;

    /// A grid over the box [lo, hi] with nothing learnt.
    RadianceGrid(const Vec3& lo, const Vec3& hi);

    /// The cell holding p, or -1 outside the box.
    int cell(const Vec3& p) const;
    int cells() const { return nx_ * ny_ * nz_; }
    /// The learnt root second moment sqrt(E[L^2]) of cell c, or -1 where nothing is learnt
    /// (c = -1 too).
    double rms(int c) const { return c >= 0 ? rms_[static_cast<std::size_t>(c)] : -1.0; }
    /// The learnt mean E[L] of cell c, or -1 where nothing is learnt.
    double mean(int c) const { return c >= 0 ? mean_[static_cast<std::size_t>(c)] : -1.0; }
    /// Cells with something learnt.
    int learnt_cells() const;

    /// One share of what a learning pass gathers.
    struct Tally {
        explicit Tally(const RadianceGrid& g);
        /// An estimate `value` (>= 0) of what is collected from p on.
        void record(const Vec3& p, double value);
        const RadianceGrid* g;
        std::vector<double> sum, sum2;
        std::vector<std::int64_t> count;
    };

    /// Adds a tally's records to what is learnt (the moments over every record learnt from).
    void learn(const Tally& t);

  private:
    Vec3 lo_;
    double inv_edge_ = 0;
    int nx_ = 1, ny_ = 1, nz_ = 1;
    std::vector<double> sum_, sum2_, mean_, rms_;
    std::vector<std::int64_t> count_;
};

}  // namespace ssslab::volpath
