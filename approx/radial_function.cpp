#include "approx/radial_function.h"

#include "approx/diffusion.h"

#include <cmath>
#include <stdexcept>
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

}  // namespace ssslab::approx
