// Batch-means statistics: every Monte Carlo estimate in ssslab carries its standard error.
//
// A run is split into batches of independent samples (photons). For each element i of a tally,
// the batch sums S_b (over n_b samples) are folded in batch order into
//     sum_i = sum_b S_b,    q_i = sum_b S_b^2 / n_b,
// from which the mean per sample is mu = sum / N (N = sum_b n_b) and, since Var(S_b) = n_b
// sigma^2 for i.i.d. samples, the per-sample variance estimate is
//     sigma^2 = (q - N mu^2) / (B - 1),     SE(mu) = sigma / sqrt(N).
// Batches may differ in size (a final partial batch). Folding in batch order makes the result
// independent of which thread computed which batch.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace ssslab {

// Regularised upper incomplete gamma Q(a, x) (series below a + 1, Lentz's continued fraction
// above; Numerical Recipes §6.2), for chi-square p-values: p = Q(dof / 2, chi2 / 2).
inline double gamma_q(double a, double x) {
    if (x <= 0) return 1.0;
    const double lg = std::lgamma(a);
    if (x < a + 1) {
        double sum = 1.0 / a, del = sum, ap = a;
        for (int n = 0; n < 100000; ++n) {
            ap += 1;
            del *= x / ap;
            sum += del;
            if (std::fabs(del) < std::fabs(sum) * 1e-15) break;
        }
        return std::max(0.0, 1.0 - sum * std::exp(-x + a * std::log(x) - lg));
    }
    const double tiny = 1e-300;
    double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        const double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::fabs(c) < tiny) c = tiny;
        d = 1 / d;
        const double del = d * c;
        h *= del;
        if (std::fabs(del - 1) < 1e-15) break;
    }
    return std::exp(-x + a * std::log(x) - lg) * h;
}

/// P(chi-square with `dof` degrees of freedom >= chi2): the p-value of a chi-square test.
inline double chi_square_p(double chi2, double dof) {
    return dof > 0 ? gamma_q(0.5 * dof, 0.5 * chi2) : 1.0;
}

/// The standard normal quantile: x with P(N(0, 1) <= x) = p (bisection on the CDF
/// 0.5 erfc(-x / sqrt 2): slow but exact to double precision).
inline double normal_quantile(double p) {
    double lo = -40, hi = 40;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

/// The per-test significance that keeps a family of `tests` independent tests at `alpha`
/// (Sidak).
inline double sidak(double alpha, int tests) {
    return 1.0 - std::pow(1.0 - alpha, 1.0 / std::max(1, tests));
}

class BatchAccumulator {
  public:
    BatchAccumulator() = default;
    explicit BatchAccumulator(size_t size) { resize(size); }

    void resize(size_t size) {
        sum_.assign(size, 0.0);
        q_.assign(size, 0.0);
        n_ = 0;
        batches_ = 0;
    }
    size_t size() const { return sum_.size(); }

    /// Fold in one batch: `s` holds size() batch sums over `n` samples.
    void add_batch(const double* s, std::uint64_t n) {
        const double inv_n = 1.0 / static_cast<double>(n);
        for (size_t i = 0; i < sum_.size(); ++i) {
            sum_[i] += s[i];
            q_[i] += s[i] * s[i] * inv_n;
        }
        n_ += n;
        ++batches_;
    }

    std::uint64_t samples() const { return n_; }
    std::uint64_t batches() const { return batches_; }

    double mean(size_t i) const { return n_ ? sum_[i] / static_cast<double>(n_) : 0.0; }
    /// Standard error of mean(i); 0 with fewer than two batches.
    double standard_error(size_t i) const {
        if (batches_ < 2) return 0.0;
        const double N = static_cast<double>(n_);
        const double mu = sum_[i] / N;
        const double ss = q_[i] - N * mu * mu;
        return ss > 0 ? std::sqrt(ss / (static_cast<double>(batches_ - 1) * N)) : 0.0;
    }

    std::vector<double> means() const {
        std::vector<double> m(size());
        for (size_t i = 0; i < size(); ++i) m[i] = mean(i);
        return m;
    }
    std::vector<double> standard_errors() const {
        std::vector<double> m(size());
        for (size_t i = 0; i < size(); ++i) m[i] = standard_error(i);
        return m;
    }

    // Raw state, for checkpoints.
    std::vector<double>& raw_sum() { return sum_; }
    std::vector<double>& raw_q() { return q_; }
    const std::vector<double>& raw_sum() const { return sum_; }
    const std::vector<double>& raw_q() const { return q_; }
    void set_counts(std::uint64_t samples, std::uint64_t batches) {
        n_ = samples;
        batches_ = batches;
    }

  private:
    std::vector<double> sum_, q_;
    std::uint64_t n_ = 0, batches_ = 0;
};

/// The own error of an image-like estimate of n elements (pixel channels): the relative RMS
/// standard error sqrt(sum SE^2 / sum v^2) of the whole, the median over the elements with
/// v > 0 and SE > 0 of SE / v (what "the image has converged to 1 %" means to a user: half the
/// pixels that see anything are within 1 %), and the relative standard error of the elements'
/// mean (their errors taken as independent). value(i) and error(i) give element i.
struct RelativeError {
    double rms = 0;           ///< sqrt(sum SE^2 / sum v^2); 0 if all v are 0
    double median = 0;        ///< median of SE / v; 0 if no element has v > 0 and SE > 0
    double mean = 0;          ///< sqrt(sum SE^2) / |sum v|; 0 if sum v is 0
    std::size_t counted = 0;  ///< elements in the median
};
template <class Value, class Error>
RelativeError relative_error(std::size_t n, const Value& value, const Error& error) {
    RelativeError r;
    double s2 = 0, v2 = 0, sum = 0;
    std::vector<double> rel;
    rel.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        const double v = value(i), e = error(i);
        s2 += e * e;
        v2 += v * v;
        sum += v;
        if (v > 0 && e > 0) rel.push_back(e / v);
    }
    r.rms = v2 > 0 ? std::sqrt(s2 / v2) : 0.0;
    r.mean = sum != 0 ? std::sqrt(s2) / std::abs(sum) : 0.0;
    r.counted = rel.size();
    if (!rel.empty()) {
        const auto mid = rel.begin() + static_cast<std::ptrdiff_t>(rel.size() / 2);
        std::nth_element(rel.begin(), mid, rel.end());
        r.median = *mid;
    }
    return r;
}

/// A weighted relative L2 distance of a curve m from a Monte Carlo reference ref,
/// E = sqrt(N / D), N = sum_k a_k (m_k - ref_k)^2, D = sum_k a_k ref_k^2 (e.g. a radial profile's
/// bins: a_k = dr_k r_k^2 for r R(r)), and with `ref_se` the standard error that the reference's
/// noise gives E (m has none), by the delta method over independent elements:
/// dE/dref_k = -a_k ((m_k - ref_k) + E^2 ref_k) / (E D). First order: valid while ref_se is small
/// against |m - ref|; E = 0 gets no standard error.
struct RelL2 {
    double value = 0, se = 0;
};
inline RelL2 weighted_rel_l2(const std::vector<double>& a, const std::vector<double>& m,
                             const std::vector<double>& ref,
                             const std::vector<double>& ref_se = {}) {
    double num = 0, den = 0;
    for (std::size_t k = 0; k < a.size(); ++k) {
        num += a[k] * (m[k] - ref[k]) * (m[k] - ref[k]);
        den += a[k] * ref[k] * ref[k];
    }
    RelL2 out;
    if (!(den > 0)) return out;
    out.value = std::sqrt(num / den);
    if (ref_se.empty() || !(out.value > 0)) return out;
    double var = 0;
    for (std::size_t k = 0; k < a.size(); ++k) {
        const double d =
            -a[k] * ((m[k] - ref[k]) + out.value * out.value * ref[k]) / (out.value * den);
        var += d * d * ref_se[k] * ref_se[k];
    }
    out.se = std::sqrt(var);
    return out;
}

}  // namespace ssslab
