// A radial profile as the integrations over a scene's surfaces read it (approx/hierarchical.h,
// approx/munoz.h): R_d(r) per RGB channel [1/mm^2] at a distance r [mm], from an MC profile's bins
// or from analytic models.
#pragma once

#include "core/profile.h"

#include <array>
#include <functional>
#include <memory>
#include <utility>

namespace ssslab::approx {

class DiffusionProfile;

/// R_d(r) per RGB channel [1/mm^2] at r [mm]: what the integration sums. Thread-safe once built.
class RadialFunction {
  public:
    /// An MC profile (core/profile.h) as its bin means: R_d(r) = the mean over the annulus holding
    /// r (piecewise constant, so that its integral over the plane is the profile's reflectance
    /// inside the grid exactly), 0 beyond the grid (the profile's `beyond` is not placed).
    static RadialFunction from_profile(const RadialProfile& p);
    /// Analytic profiles, one per channel, whose lengths are in mm (coefficients per mm).
    /// R_d is per unit power entering (approx/diffusion.h's convention).
    static RadialFunction from_diffusion(
        const std::array<std::shared_ptr<const DiffusionProfile>, 3>& channels);
    /// f tabulated at n radii spaced geometrically from r_min to r_max [mm] (0 < r_min < r_max,
    /// n >= 2) and interpolated log-log between them (linearly where either value is 0); f(r_min)
    /// below r_min, 0 beyond r_max. For analytic profiles whose every evaluation integrates (pbd)
    /// where millions of evaluations are needed; a profile ~ 1/r at 0 loses only its integral
    /// inside r_min beyond the constant.
    static RadialFunction tabulated(const RadialFunction& f, double r_min_mm, double r_max_mm,
                                    int n);
    /// Any function of r [mm] returning R_d per channel [1/mm^2].
    explicit RadialFunction(std::function<std::array<double, 3>(double)> f) : f_(std::move(f)) {}

    std::array<double, 3> operator()(double r_mm) const { return f_(r_mm); }

  private:
    std::function<std::array<double, 3>(double)> f_;
};

}  // namespace ssslab::approx
