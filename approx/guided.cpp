#include "approx/models.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <Eigen/QR>

#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace ssslab::approx {

namespace {

// Minimise sum_i D_i a_i^2 - 2 B_i a_i subject to sum_i a_i = s and a >= 0:
// a_i = max(0, (B_i - lambda) / D_i) with lambda such that the sum is s (it decreases in lambda).
Eigen::VectorXd constrained_step(const Eigen::VectorXd& B, const Eigen::VectorXd& D, double s) {
    const Eigen::Index n = B.size();
    auto total = [&](double lambda) {
        double t = 0;
        for (Eigen::Index i = 0; i < n; ++i)
            if (D(i) > 0) t += std::max(0.0, (B(i) - lambda) / D(i));
        return t;
    };
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (Eigen::Index i = 0; i < n; ++i) {
        if (!(D(i) > 0)) continue;
        lo = std::min(lo, B(i) - s * D(i));  // there, the i-th term alone reaches s
        hi = std::max(hi, B(i));             // there, every term is 0
    }
    if (!(lo < hi)) throw std::runtime_error("guided optimization: degenerate weights");
    for (int it = 0; it < 200 && hi - lo > 0; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break;
        (total(mid) > s ? lo : hi) = mid;
    }
    const double lambda = 0.5 * (lo + hi);
    Eigen::VectorXd a(n);
    for (Eigen::Index i = 0; i < n; ++i)
        a(i) = D(i) > 0 ? std::max(0.0, (B(i) - lambda) / D(i)) : 0.0;
    // Remove the last rounding of the sum (a proportional correction keeps a >= 0).
    const double sum = a.sum();
    if (sum > 0) a *= s / sum;
    return a;
}

}  // namespace

namespace {

struct LevelResult {
    Eigen::VectorXd a;
    int iterations = 0;
    double change = 0, objective = 0;
};

// Solve the guided problem for a quadrant q (4 sum q = 1) from the start a (sum a = 1/2).
constexpr double kTolerance = 1e-12;  // relative L1 change of a between steps

// The guide Gamma(x, y; k, b) on x, y in [-1, 1] spanning the grid, cell centres at (i + 1/2) / n
// [Freude14 Eq. 5.20]. It is symmetric: column i is row i, so the products read contiguous
// columns. Only j >= i is evaluated (the radial power is the costly part), then mirrored.
Eigen::MatrixXd build_guide(int n, const GuideParams& g) {
    Eigen::VectorXd x(n), sx(n);
    for (int i = 0; i < n; ++i) {
        x(i) = (i + 0.5) / n;
        sx(i) = g.b > 0 ? 1.0 - std::exp(-g.b * x(i) * x(i)) : 1.0;
    }
    Eigen::MatrixXd W(n, n);
    const bool even_integer_k = g.k == std::floor(g.k) && static_cast<int>(g.k) % 2 == 0;
    tbb::parallel_for(0, n, [&](int j) {
        for (int i = 0; i <= j; ++i) {
            const double r2 = x(i) * x(i) + x(j) * x(j);
            double radial;
            if (g.k == 0)
                radial = 1.0;
            else if (g.k == 1)
                radial = std::sqrt(r2);
            else if (even_integer_k)
                radial = std::pow(r2, static_cast<int>(g.k) / 2);
            else
                radial = std::pow(r2, 0.5 * g.k);
            W(i, j) = radial * sx(i) * sx(j);
        }
    });
    tbb::parallel_for(0, n, [&](int j) {
        for (int i = j + 1; i < n; ++i) W(i, j) = W(j, i);
    });
    return W;
}

// The guide depends on the grid size and (k, b) only, not on the kernel: the three channels of a
// material share it. The last two guides built (a fine level and its coarse level) are kept.
std::shared_ptr<const Eigen::MatrixXd> guide_matrix(int n, const GuideParams& g) {
    struct Entry {
        int n;
        double k, b;
        std::shared_ptr<const Eigen::MatrixXd> w;
    };
    static std::mutex mutex;
    static std::deque<Entry> cache;
    {
        std::lock_guard<std::mutex> lock(mutex);
        for (const Entry& e : cache)
            if (e.n == n && e.k == g.k && e.b == g.b) return e.w;
    }
    auto w = std::make_shared<const Eigen::MatrixXd>(build_guide(n, g));
    std::lock_guard<std::mutex> lock(mutex);
    cache.push_front({n, g.k, g.b, w});
    if (cache.size() > 2) cache.pop_back();
    return w;
}

LevelResult solve_level(const Eigen::MatrixXd& q, const GuideParams& g, Eigen::VectorXd a,
                        double tolerance) {
    const int n = static_cast<int>(q.rows());
    const std::shared_ptr<const Eigen::MatrixXd> guide = guide_matrix(n, g);
    const Eigen::MatrixXd& W = *guide;
    // B = (W o q) b and D = W (b o b), in one parallel pass over the columns of W and q (both
    // symmetric).
    auto products = [&](const Eigen::VectorXd& b, Eigen::VectorXd& B, Eigen::VectorXd& D) {
        const Eigen::VectorXd bb = b.cwiseProduct(b);
        B.resize(n);
        D.resize(n);
        tbb::parallel_for(0, n, [&](int i) {
            const double* w = W.col(i).data();
            const double* qc = q.col(i).data();
            double sb = 0, sd = 0;
            for (int j = 0; j < n; ++j) {
                sb += w[j] * qc[j] * b(j);
                sd += w[j] * bb(j);
            }
            B(i) = sb;
            D(i) = sd;
        });
    };
    const double s = 0.5;
    // The damped alternating step: the best a for the other factor b fixed (a separable
    // quadratic with the constraint and bounds), averaged with b. Its fixed point a = b is a KKT
    // point of the symmetric problem. Anderson acceleration (depth 6) of this map, every
    // accelerated iterate projected back onto {a >= 0, sum a = 1/2}, restarted when the residual
    // grows.
    auto step = [&](const Eigen::VectorXd& b) {
        Eigen::VectorXd B, D;
        products(b, B, D);
        return Eigen::VectorXd(0.5 * (constrained_step(B, D, s) + b));
    };
    constexpr int kDepth = 6;
    std::vector<Eigen::VectorXd> dx, df;  // differences of iterates and of residuals
    Eigen::VectorXd x_prev, f_prev;
    LevelResult res;
    double change = 1, last_residual = std::numeric_limits<double>::infinity();
    int it = 0;
    for (; it < 5000; ++it) {
        const Eigen::VectorXd t = step(a);
        const Eigen::VectorXd f = t - a;  // residual
        change = f.lpNorm<1>() / a.lpNorm<1>();
        if (change <= tolerance) {
            a = t;
            break;
        }
        if (f.lpNorm<1>() > last_residual) {  // the accelerated step overshot: restart
            dx.clear(), df.clear();
            x_prev.resize(0);
            last_residual = f.lpNorm<1>();
            a = t;
            continue;
        }
        last_residual = f.lpNorm<1>();
        if (x_prev.size()) {
            dx.push_back(a - x_prev);
            df.push_back(f - f_prev);
            if (static_cast<int>(dx.size()) > kDepth) dx.erase(dx.begin()), df.erase(df.begin());
        }
        x_prev = a;
        f_prev = f;
        Eigen::VectorXd next = t;
        if (!df.empty()) {
            const int m = static_cast<int>(df.size());
            Eigen::MatrixXd F(a.size(), m), X(a.size(), m);
            for (int c = 0; c < m; ++c)
                F.col(c) = df[static_cast<size_t>(c)], X.col(c) = dx[static_cast<size_t>(c)];
            const Eigen::VectorXd gamma = F.colPivHouseholderQr().solve(f);
            Eigen::VectorXd aa = a + f - (X + F) * gamma;
            for (Eigen::Index i = 0; i < aa.size(); ++i) aa(i) = std::max(0.0, aa(i));
            if (aa.sum() > 0) next = aa * (s / aa.sum());
        }
        a = next;
    }
    res.a = a;
    res.iterations = it;
    res.change = change;
    // The objective over the whole kernel (four quadrants), without n x n temporaries.
    res.objective = 4.0 * tbb::parallel_reduce(
                              tbb::blocked_range<int>(0, n), 0.0,
                              [&](const tbb::blocked_range<int>& r, double acc) {
                                  for (int j = r.begin(); j < r.end(); ++j)
                                      for (int i = 0; i < n; ++i) {
                                          const double e = q(i, j) - a(i) * a(j);
                                          acc += W(i, j) * e * e;
                                      }
                                  return acc;
                              },
                              std::plus<double>());
    return res;
}

}  // namespace

ModelResult guided(const Kernel2D& k, const GuideParams& g) {
    const auto t0 = std::chrono::steady_clock::now();
    if (!(g.k >= 0 && g.k <= 4))
        throw std::invalid_argument("guided optimization: k outside [0, 4]");
    if (!(g.b >= 0)) throw std::invalid_argument("guided optimization: b < 0");
    // No truncation of the domain: where K vanishes the optimum is not always a = 0 (when the
    // constraint must add mass, its multiplier is negative and the cheapest place for mass is
    // where the weights are small, far out included).
    const Eigen::MatrixXd& q = k.quadrant();
    Eigen::VectorXd a = 2.0 * q.rowwise().sum();  // the pre-integrated kernel as first guess
    a *= 0.5 / a.sum();
    // Two levels on large grids: the problem on 2 x 2 aggregated cells (the guide evaluated at the
    // coarse cells' centres) gives the fine level a start close to its optimum, so the fine level,
    // whose every step reads the n x n weights, needs a few steps only. The answer is the fine
    // level's own fixed point, to the same tolerance.
    if (q.rows() >= 512) {
        const Eigen::Index m = q.rows() / 2;
        Eigen::MatrixXd qc(m, m);
        for (Eigen::Index j = 0; j < m; ++j)
            for (Eigen::Index i = 0; i < m; ++i)
                qc(i, j) = q(2 * i, 2 * j) + q(2 * i + 1, 2 * j) + q(2 * i, 2 * j + 1) +
                           q(2 * i + 1, 2 * j + 1);
        Eigen::VectorXd ac(m);
        for (Eigen::Index i = 0; i < m; ++i) ac(i) = a(2 * i) + a(2 * i + 1);
        ac *= 0.5 / ac.sum();
        const LevelResult coarse = solve_level(qc, g, ac, 1e-6);
        for (Eigen::Index i = 0; i < m; ++i) a(2 * i) = a(2 * i + 1) = 0.5 * coarse.a(i);
        if (q.rows() % 2) a(q.rows() - 1) = a(q.rows() - 2);
        a *= 0.5 / a.sum();
    }
    const LevelResult res = solve_level(q, g, a, kTolerance);
    a = res.a;
    const int n = k.n();
    const double change = res.change;
    const int it = res.iterations;
    ModelResult r;
    r.kernel.model = "guided-k" + std::to_string(g.k) + "-b" + std::to_string(g.b);
    r.kernel.h_mm = k.h_mm();
    r.kernel.n = n;
    SeparableTerm t;
    t.a.assign(a.data(), a.data() + n);
    r.kernel.terms.push_back(std::move(t));
    const double l1 = r.kernel.l1();
    r.info["constraint_error"] = std::fabs(l1 - 1.0);
    r.info["iterations"] = it;
    r.info["last_change"] = change;
    r.info["objective"] = res.objective;
    r.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace ssslab::approx
