// The manual (artist-friendly) two-Gaussian model of Jorge Jimenez [Freude14 §5.4, Eq. 5.21]:
// A_m(x, y) = a_m(x) a_m(y), a_m(x) = w G(x, tau_n) + (1 - w) G(x, tau_f).
#include "approx/models.h"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace ssslab::approx {

namespace {

// Mass of the unit-integral 1D Gaussian of standard deviation `sigma` over [x0, x1], 0 <= x0 <
// x1: erf differences near the centre, erfc differences in the tail (no cancellation there).
double gaussian_cell_mass(double x0, double x1, double sigma) {
    const double s = 1.0 / (sigma * std::sqrt(2.0));
    const double u0 = x0 * s, u1 = x1 * s;
    if (u0 < 0.5) return 0.5 * (std::erf(u1) - std::erf(u0));
    return 0.5 * (std::erfc(u0) - std::erfc(u1));
}

}  // namespace

ModelResult manual_two_gaussian(const Kernel2D& k, double sqrt_tau_near_mm, double sqrt_tau_far_mm,
                                double w, bool normalise) {
    const auto t0 = std::chrono::steady_clock::now();
    if (!(sqrt_tau_near_mm > 0) || !std::isfinite(sqrt_tau_near_mm) || !(sqrt_tau_far_mm > 0) ||
        !std::isfinite(sqrt_tau_far_mm))
        throw std::invalid_argument("manual_two_gaussian: sqrt(tau) must be positive and finite");
    if (!(w >= 0 && w <= 1))
        throw std::invalid_argument("manual_two_gaussian: w = " + std::to_string(w) +
                                    " is outside [0, 1]");
    const int n = k.n();
    const double h = k.h_mm();
    ModelResult r;
    r.kernel.model = "manual";
    r.kernel.h_mm = h;
    r.kernel.n = n;
    SeparableTerm t;
    t.a.resize(static_cast<size_t>(n));
    // Exact cell masses of each Gaussian over [i h, (i + 1) h]. Each Gaussian is then normalised
    // on the grid (its half vector sums to 1/2), so the kernel has unit L1 and w stays the share
    // of energy in the near Gaussian: the thesis's "enforced energy conservation via
    // normalization" [Freude14 §5.4]. What a Gaussian would lose beyond the grid is reported.
    std::vector<double> gn(static_cast<size_t>(n)), gf(static_cast<size_t>(n));
    double sn = 0, sf = 0;
    for (int i = 0; i < n; ++i) {
        sn += gn[static_cast<size_t>(i)] = gaussian_cell_mass(i * h, (i + 1) * h, sqrt_tau_near_mm);
        sf += gf[static_cast<size_t>(i)] = gaussian_cell_mass(i * h, (i + 1) * h, sqrt_tau_far_mm);
    }
    const double cn = normalise ? 0.5 / sn : 1.0, cf = normalise ? 0.5 / sf : 1.0;
    for (size_t i = 0; i < gn.size(); ++i) t.a[i] = w * cn * gn[i] + (1.0 - w) * cf * gf[i];
    r.kernel.terms.push_back(std::move(t));
    // 1 - (the full 1D sum before normalisation), from the tails beyond n h on both sides: erfc,
    // not a difference.
    const double e = n * h / std::sqrt(2.0);
    r.info["mass_outside_grid"] =
        w * std::erfc(e / sqrt_tau_near_mm) + (1.0 - w) * std::erfc(e / sqrt_tau_far_mm);
    r.info["l1"] = r.kernel.l1();
    r.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace ssslab::approx
