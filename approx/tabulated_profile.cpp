#include "approx/tabulated_profile.h"

#include "approx/diffusion_detail.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace ssslab::approx {

std::vector<double> TabulatedProfile::radii(double r_min, double r_max, int n) {
    if (!(r_min > 0 && r_max > r_min && std::isfinite(r_max)) || n < 4)
        throw std::invalid_argument("a profile table needs 0 < r_min < r_max and 4 or more radii");
    std::vector<double> r(static_cast<size_t>(n));
    const double a = std::log(r_min), step = (std::log(r_max) - a) / (n - 1);
    for (int k = 0; k < n; ++k) r[static_cast<size_t>(k)] = std::exp(a + step * k);
    r.front() = r_min;
    r.back() = r_max;
    return r;
}

TabulatedProfile::TabulatedProfile(std::string name, const DiffusionMedium& m, double r_min,
                                   double r_max, std::vector<double> values, bool single_scattering,
                                   double accuracy)
    : DiffusionProfile(m),
      name_(std::move(name)),
      v_(std::move(values)),
      single_(single_scattering),
      accuracy_(accuracy) {
    if (!(accuracy >= 0 && accuracy < 1))
        throw std::invalid_argument(name_ + ": a table's accuracy must lie in [0, 1)");
    const std::vector<double> r = radii(r_min, r_max, static_cast<int>(v_.size()));
    ln_min_ = std::log(r_min);
    ln_max_ = std::log(r_max);
    h_ = (ln_max_ - ln_min_) / static_cast<double>(v_.size() - 1);
    ln_v_.resize(v_.size());
    for (size_t k = 0; k < v_.size(); ++k) {
        if (!std::isfinite(v_[k])) {
            std::ostringstream os;
            os.precision(9);
            os << name_ << ": R_d(" << r[k] << ") = " << v_[k] << " (not a finite number)";
            throw std::invalid_argument(os.str());
        }
        ln_v_[k] = v_[k] > 0 ? std::log(v_[k]) : std::numeric_limits<double>::quiet_NaN();
    }
    std::vector<double> breaks;
    for (double t = ln_min_; t < ln_max_; t += 1) breaks.push_back(t);
    breaks.push_back(ln_max_);
    total_ = diffusion_detail::kPi * r_min * r_min * v_.front() +
             diffusion_detail::integrate(
                 [&](double t) {
                     const double x = std::exp(t);
                     return 2 * diffusion_detail::kPi * x * x * eval_rd(x);
                 },
                 breaks, std::max(1e-10, accuracy_));
}

double TabulatedProfile::eval_rd(double r) const {
    const double u = std::log(r);
    if (!(u > ln_min_)) return v_.front();
    if (u > ln_max_) return 0;
    const auto last = static_cast<std::ptrdiff_t>(v_.size()) - 1;
    const double s = (u - ln_min_) / h_;
    const auto k = std::min<std::ptrdiff_t>(static_cast<std::ptrdiff_t>(s), last - 1);
    const double t = s - static_cast<double>(k);
    const auto at = [&](std::ptrdiff_t i) {
        return static_cast<size_t>(std::clamp<std::ptrdiff_t>(i, 0, last));
    };
    const double y0 = ln_v_[at(k - 1)], y1 = ln_v_[at(k)], y2 = ln_v_[at(k + 1)],
                 y3 = ln_v_[at(k + 2)];
    if (std::isnan(y0) || std::isnan(y1) || std::isnan(y2) || std::isnan(y3))
        return v_[at(k)] + t * (v_[at(k + 1)] - v_[at(k)]);
    // Catmull-Rom: tangents (y2 - y0)/2 and (y3 - y1)/2 (one-sided at the table's ends through
    // the clamped indices).
    const double m1 = (y2 - y0) / (k == 0 ? 1 : 2), m2 = (y3 - y1) / (k + 1 == last ? 1 : 2);
    const double t2 = t * t, t3 = t2 * t;
    const double y = (2 * t3 - 3 * t2 + 1) * y1 + (t3 - 2 * t2 + t) * m1 + (-2 * t3 + 3 * t2) * y2 +
                     (t3 - t2) * m2;
    return std::exp(y);
}

}  // namespace ssslab::approx
