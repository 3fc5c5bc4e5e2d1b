#include "approx/separable.h"

#include <algorithm>
#include <cmath>

namespace ssslab::approx {

double SeparableKernel::at(int x, int y) const {
    const size_t i = static_cast<size_t>(Kernel2D::fold(x)),
                 j = static_cast<size_t>(Kernel2D::fold(y));
    double v = 0;
    for (const auto& t : terms) v += t.sign * t.a[i] * t.a[j];
    return v;
}

Eigen::MatrixXd SeparableKernel::quadrant() const {
    Eigen::MatrixXd q = Eigen::MatrixXd::Zero(n, n);
    for (const auto& t : terms) {
        const Eigen::Map<const Eigen::VectorXd> a(t.a.data(), n);
        q.noalias() += t.sign * a * a.transpose();
    }
    return q;
}

double SeparableKernel::sum() const {
    double s = 0;
    for (const auto& t : terms) {
        double h = 0;
        for (double v : t.a) h += v;
        s += t.sign * 4.0 * h * h;
    }
    return s;
}

double SeparableKernel::l1() const {
    if (terms.size() == 1) {  // one term: |a(x) a(y)| = |a(x)| |a(y)|
        double h = 0;
        for (double v : terms[0].a) h += std::fabs(v);
        return 4.0 * h * h;
    }
    return 4.0 * quadrant().cwiseAbs().sum();
}

void SeparableKernel::scale(double f) {
    const double s = std::sqrt(std::fabs(f));
    for (auto& t : terms) {
        for (double& v : t.a) v *= s;
        if (f < 0) t.sign = -t.sign;
    }
}

KernelErrors kernel_errors(const Kernel2D& k, const SeparableKernel& a) {
    const Eigen::MatrixXd d = k.quadrant() - a.quadrant();
    KernelErrors e;
    const double cells = 4.0 * static_cast<double>(k.n()) * k.n();
    e.rms = std::sqrt(4.0 * d.squaredNorm() / cells);
    e.max_abs = d.cwiseAbs().maxCoeff();
    e.l1_error = std::fabs(a.sum() - 1.0);
    // Radial asymmetry: a radially symmetric kernel has the same value on the axis at radius r as
    // on the diagonal at radius r. Compare A(r, 0) with A on the diagonal at the same radius
    // (linear interpolation along the diagonal cells), relative to K on the axis.
    const int n = k.n();
    double num = 0, den = 0;
    for (int i = 0; i < n; ++i) {
        const double r = (i + 0.5);                     // in cells, along the axis (y = 0.5)
        const double rr = std::sqrt(r * r + 0.25);      // radius of axis cell (i, 0)
        const double dpos = rr / std::sqrt(2.0) - 0.5;  // diagonal cell index at that radius
        if (dpos < 0 || dpos > n - 1) continue;
        const int d0 = static_cast<int>(dpos);
        const int d1 = std::min(n - 1, d0 + 1);
        const double t = dpos - d0;
        const double diag = (1 - t) * a.at(d0, d0) + t * a.at(d1, d1);
        const double diff = a.at(i, 0) - diag;
        num += diff * diff;
        den += k.at(i, 0) * k.at(i, 0);
    }
    e.radial_asymmetry = den > 0 ? std::sqrt(num / den) : 0.0;
    return e;
}

}  // namespace ssslab::approx
