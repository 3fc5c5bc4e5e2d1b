#include "approx/kernel2d.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ssslab::approx {

KernelGrid KernelGrid::from_profile(const RadialProfile& p, int refine) {
    if (refine < 1) throw std::invalid_argument("KernelGrid: refine < 1");
    KernelGrid g;
    g.h_mm = p.dr_cm * 10.0 / refine;
    g.n = p.nr * refine;
    return g;
}

Kernel2D::Kernel2D(const RadialProfile& p, int c, const KernelGrid& grid) : h_(grid.h_mm) {
    const int n = grid.n;
    if (n < 1 || !(h_ > 0)) throw std::invalid_argument("Kernel2D: empty grid");
    const double dr = p.dr_cm * 10.0;  // mm
    if (c < 0 || c > 2)
        throw std::invalid_argument("Kernel2D: channel " + std::to_string(c) + " is not 0, 1 or 2");
    const std::vector<double>& R = p.rd_per_cm2[c];
    if (R.size() < static_cast<size_t>(std::max(p.nr, 0)))
        throw std::invalid_argument("Kernel2D: channel " + std::to_string(c) + " of profile '" +
                                    p.name + "' has " + std::to_string(R.size()) +
                                    " bins, fewer than nr = " + std::to_string(p.nr));
    const double to_mm2 = 0.01;  // 1/cm^2 -> 1/mm^2
    const int s = std::max(2, static_cast<int>(std::ceil(2.0 * h_ / dr)));
    q_.resize(n, n);
    // A cell's mass is h^2 times the mean of the profile over s x s sub-samples. The quadrant is
    // symmetric, so only j >= i is computed.
    std::vector<double> off(static_cast<size_t>(s));
    for (int k = 0; k < s; ++k) off[static_cast<size_t>(k)] = (k + 0.5) / s;
    auto value = [&](double r) {
        const double b = r / dr;
        if (!(b < static_cast<double>(p.nr))) return 0.0;
        const double v = R[static_cast<size_t>(b)];
        return std::isfinite(v) ? v * to_mm2 : 0.0;
    };
    // The total is accumulated with Neumaier compensation: a quadrant has up to ~10^7 cells and the
    // normalisation must hold to near machine precision for the image-space tests.
    double total = 0, carry = 0;
    auto accumulate = [&](double v) {
        const double t = total + v;
        carry += std::abs(total) >= std::abs(v) ? (total - t) + v : (v - t) + total;
        total = t;
    };
    for (int i = 0; i < n; ++i)
        for (int j = i; j < n; ++j) {
            double sum = 0;
            for (int a = 0; a < s; ++a)
                for (int b = 0; b < s; ++b) {
                    const double x = (i + off[static_cast<size_t>(a)]) * h_;
                    const double y = (j + off[static_cast<size_t>(b)]) * h_;
                    sum += value(std::sqrt(x * x + y * y));
                }
            const double mass = sum / (s * s) * h_ * h_;
            q_(i, j) = q_(j, i) = mass;
            accumulate((i == j ? 4.0 : 8.0) * mass);
        }
    total += carry;
    raw_l1_ = total;
    if (!(total > 0) || !std::isfinite(total))
        throw std::invalid_argument("Kernel2D: channel " + std::to_string(c) + " of profile '" +
                                    p.name + "' has no reflectance on the grid");
    q_ /= total;
}

Kernel2D::Kernel2D(Eigen::MatrixXd quadrant, double h_mm) : q_(std::move(quadrant)), h_(h_mm) {
    if (q_.rows() != q_.cols() || q_.rows() == 0)
        throw std::invalid_argument("Kernel2D: quadrant must be square and non-empty");
    const double total = 4.0 * q_.sum();
    raw_l1_ = total;
    if (!(total > 0) || !std::isfinite(total))
        throw std::invalid_argument("Kernel2D: the quadrant has no positive mass");
    q_ /= total;
}

Eigen::MatrixXd Kernel2D::full() const {
    const int m = size();
    Eigen::MatrixXd f(m, m);
    for (int x = 0; x < m; ++x)
        for (int y = 0; y < m; ++y) f(x, y) = at(x - n(), y - n());
    return f;
}

}  // namespace ssslab::approx
