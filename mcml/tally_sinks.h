// Where the transport deposits weight: the full .mco arrays or a radial profile.
#pragma once

#include "mcml/tally.h"
#include "mcml/transport.h"

#include <array>
#include <cmath>
#include <vector>

namespace ssslab::mcml {

/// The original's arrays A_rz, Rd_ra, Tt_ra; photons outside the grid go into the last bins
/// (MCML's Drop(), RecordR(), RecordT()). In compatibility mode the indices are computed with
/// the original's divisions; a second target (a batch tally, for standard errors) may be given.
template <bool kCompat>
class FullSink {
  public:
    FullSink(const RunSpec& run, const TallyLayout& layout, double* primary,
             double* secondary = nullptr)
        : L_(layout),
          t0_(primary),
          t1_(secondary),
          dz_(run.grid.dz),
          dr_(run.grid.dr),
          da_(0.5 * (kCompat ? kMcmlPi : kPi) / run.grid.na),
          inv_dz_(1.0 / dz_),
          inv_dr_(1.0 / dr_),
          inv_da_(1.0 / da_) {
        if constexpr (!kCompat) {
            // cos(k da) for k = 1 .. na-1, descending, padded with -inf to a power of two.
            size_t n = 1;
            while (n < static_cast<size_t>(run.grid.na)) n *= 2;
            cos_bounds_.assign(n, -HUGE_VAL);
            for (int k = 1; k < run.grid.na; ++k)
                cos_bounds_[static_cast<size_t>(k) - 1] = std::cos(k * da_);
        }
    }

    void absorb(const Photon& p, double dwa) { deposit(p.x, p.y, p.z, dwa); }
    void reflect(const Photon& p) { exit(L_.rd_ra, p, angle_index(-p.uz)); }
    void transmit(const Photon& p) { exit(L_.tt_ra, p, angle_index(p.uz)); }

    /// Exit-angle bin of a photon leaving with cosine c to the normal: floor(acos(c) / da),
    /// clamped to na - 1. The default mode counts the bin boundaries cos(k da) >= c instead
    /// (a branch-free binary search, no acos).
    int angle_index(double c) const {
        if constexpr (kCompat) {
            const double iad = std::acos(c) / da_;
            return iad > L_.na - 1 ? L_.na - 1 : static_cast<int>(iad);
        } else {
            size_t lo = 0;
            for (size_t step = cos_bounds_.size() / 2 + (cos_bounds_.size() == 1); step > 0;
                 step /= 2)
                lo += cos_bounds_[lo + step - 1] >= c ? step : 0;
            return static_cast<int>(lo);
        }
    }

  private:
    void deposit(double x, double y, double z, double dwa) {
        const double izd = kCompat ? z / dz_ : z * inv_dz_;
        const int iz = izd > L_.nz - 1 ? L_.nz - 1 : static_cast<int>(izd);
        const int ir = radial_index(x, y);
        add(L_.a_rz + static_cast<size_t>(ir) * static_cast<size_t>(L_.nz) +
                static_cast<size_t>(iz),
            dwa);
    }
    int radial_index(double x, double y) const {
        const double rr = std::sqrt(x * x + y * y);
        const double ird = kCompat ? rr / dr_ : rr * inv_dr_;
        return ird > L_.nr - 1 ? L_.nr - 1 : static_cast<int>(ird);
    }
    void exit(size_t base, const Photon& p, int ia) {
        const int ir = radial_index(p.x, p.y);
        add(base + static_cast<size_t>(ir) * static_cast<size_t>(L_.na) + static_cast<size_t>(ia),
            p.w * (1.0 - 0.0));  // RecordR/RecordT with Refl = 0
    }
    void add(size_t i, double w) {
        t0_[i] += w;
        if (t1_) t1_[i] += w;
    }

    const TallyLayout& L_;
    double* t0_;
    double* t1_;
    double dz_, dr_, da_, inv_dz_, inv_dr_, inv_da_;
    std::vector<double> cos_bounds_;
};

/// Radial reflectance and transmittance with an overflow bin, and absorption per layer.
class ProfileSink {
  public:
    ProfileSink(const RunSpec& run, const TallyLayout& layout, double* t)
        : L_(layout), t_(t), inv_dr_(1.0 / run.grid.dr) {}

    void absorb(const Photon& p, double dwa) {
        t_[L_.a_layer + static_cast<size_t>(p.layer)] += dwa;
    }
    void reflect(const Photon& p) { t_[L_.rd_r + index(p)] += p.w; }
    void transmit(const Photon& p) { t_[L_.tt_r + index(p)] += p.w; }

  private:
    size_t index(const Photon& p) const {
        const double ird = std::sqrt(p.x * p.x + p.y * p.y) * inv_dr_;
        return ird >= L_.nr ? static_cast<size_t>(L_.nr) : static_cast<size_t>(ird);
    }
    const TallyLayout& L_;
    double* t_;
    double inv_dr_;
};

}  // namespace ssslab::mcml
