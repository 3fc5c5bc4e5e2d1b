#include "approx/models.h"

#include <chrono>
#include <cmath>

namespace ssslab::approx {

ModelResult ssss_skin_kernel(const Kernel2D& k, int channel, const SsssSkinParams& p) {
    const auto t0 = std::chrono::steady_clock::now();
    // The demo's profile: d'Eon's skin Gaussians (variances in mm^2), red weights, the first
    // (0.233, 0.0064) left to the strength parameter as the demo does [Freude14 Eq. 4.8].
    static const double kWeight[5] = {0.100, 0.118, 0.113, 0.358, 0.078};
    static const double kVariance[5] = {0.0484, 0.187, 0.567, 1.99, 7.41};
    const double t = p.strength[static_cast<size_t>(channel)];
    const double scale = 0.001 + p.falloff[static_cast<size_t>(channel)];
    const double h = k.h_mm();
    const int n = k.n();
    // p(x / scale) integrated over [i h, (i+1) h]: each Gaussian exp(-x^2 / (2 v scale^2)) has
    // the integral sigma sqrt(2 pi) (Phi(b / sigma) - Phi(a / sigma)), sigma = sqrt(v) scale.
    std::vector<double> a(static_cast<size_t>(n), 0.0);
    double total = 0;  // over the whole line
    for (int g = 0; g < 5; ++g) {
        const double sigma = std::sqrt(kVariance[g]) * scale;
        const double amp = kWeight[g] / (2 * M_PI * kVariance[g]) * sigma * std::sqrt(2 * M_PI);
        total += amp;
        for (int i = 0; i < n; ++i) {
            const double lo = i * h / (sigma * std::sqrt(2.0)),
                         hi = (i + 1) * h / (sigma * std::sqrt(2.0));
            a[static_cast<size_t>(i)] += amp * 0.5 * (std::erf(hi) - std::erf(lo));
        }
    }
    for (double& v : a) v *= t / total;
    a[0] += 0.5 * (1.0 - t);  // the delta, split between the cells at +-h/2
    ModelResult r;
    r.kernel.model = "ssss_skin";
    r.kernel.h_mm = h;
    r.kernel.n = n;
    r.kernel.terms.push_back({a, 1.0});
    r.info["strength"] = t;
    r.info["falloff"] = p.falloff[static_cast<size_t>(channel)];
    double half = 0;
    for (double v : a) half += v;
    r.info["mass_outside_grid"] = 1.0 - 2.0 * half;
    r.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace ssslab::approx
