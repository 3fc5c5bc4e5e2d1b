#include "approx/radial_function.h"

#include "approx/diffusion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace ssslab::approx {

// ---- Radial functions ---------------------------------------------------------------------------

RadialFunction RadialFunction::from_profile(const RadialProfile& p) {
    if (!(p.dr_cm > 0) || p.nr < 1)
        throw std::invalid_argument("RadialFunction: profile '" + p.name + "' has no bins");
    for (int c = 0; c < 3; ++c)
        if (p.rd_per_cm2[c].size() != static_cast<size_t>(p.nr))
            throw std::invalid_argument("RadialFunction: profile '" + p.name +
                                        "' has a channel with the wrong number of bins");
    const double dr_mm = 10 * p.dr_cm;
    std::vector<std::array<double, 3>> bins(static_cast<size_t>(p.nr));
    for (int i = 0; i < p.nr; ++i)
        for (int c = 0; c < 3; ++c) bins[i][c] = p.rd_per_cm2[c][i] / 100;  // 1/cm^2 -> 1/mm^2
    return RadialFunction([bins = std::move(bins), dr_mm](double r) -> std::array<double, 3> {
        const double i = std::floor(r / dr_mm);
        if (!(i >= 0) || i >= static_cast<double>(bins.size())) return {0, 0, 0};
        return bins[static_cast<size_t>(i)];
    });
}

RadialFunction RadialFunction::from_diffusion(
    const std::array<std::shared_ptr<const DiffusionProfile>, 3>& channels) {
    for (const auto& c : channels)
        if (!c) throw std::invalid_argument("RadialFunction: a channel without a profile");
    return RadialFunction([channels](double r) -> std::array<double, 3> {
        return {channels[0]->rd(r), channels[1]->rd(r), channels[2]->rd(r)};
    });
}

RadialFunction RadialFunction::tabulated(const RadialFunction& f, double r_min, double r_max,
                                         int n) {
    if (!(r_min > 0) || !(r_max > r_min) || !std::isfinite(r_max) || n < 2)
        throw std::invalid_argument("RadialFunction::tabulated: needs 0 < r_min < r_max, n >= 2");
    const double step = std::log(r_max / r_min) / (n - 1);
    std::vector<std::array<double, 3>> v(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
        const double r = i == n - 1 ? r_max : r_min * std::exp(step * i);
        v[static_cast<size_t>(i)] = f(r);
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(v[static_cast<size_t>(i)][c]) || v[static_cast<size_t>(i)][c] < 0)
                throw std::invalid_argument(
                    "RadialFunction::tabulated: the profile is negative or not finite at r = " +
                    std::to_string(r) + " mm");
    }
    return RadialFunction([v = std::move(v), r_min, r_max, step](double r) {
        if (!(r <= r_max)) return std::array<double, 3>{0, 0, 0};
        if (!(r > r_min)) return v.front();
        const double u = std::log(r / r_min) / step;
        const size_t i = std::min(static_cast<size_t>(u), v.size() - 2);
        const double s = u - static_cast<double>(i);
        std::array<double, 3> out{};
        for (int c = 0; c < 3; ++c) {
            const double a = v[i][c], b = v[i + 1][c];
            out[c] = a > 0 && b > 0 ? a * std::pow(b / a, s) : a + (b - a) * s;
        }
        return out;
    });
}

}  // namespace ssslab::approx
