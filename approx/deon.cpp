// d'Eon & Luebke's sum of 2D Gaussians [d'Eon & Luebke 2007; Freude14 Eq. 4.15]: K(x, y) ~
// A_g(x, y) = sum_i w_i G(x, y; tau_i), G(x, y; tau) = exp(-(x^2 + y^2) / (2 tau)) / (2 pi tau)
// = g(x; tau) g(y; tau), so each Gaussian is one separable term sqrt(w_i) g_i (x) sqrt(w_i) g_i
// (y).
//
// The fit minimises the 2D L2 error over the grid cells with sum w = ||K||_1 = 1 and w >= 0. The
// objective is evaluated on a coarsened grid (block sums of the quadrant, at most kMaxCoarse cells
// per side) against the Gaussians' exact masses over the same cells (products of 1D erf cell
// integrals). For given variances the weights solve a small convex QP exactly (enumeration of
// supports, N <= 6); the log-variances are searched by Nelder-Mead. Mixtures are grown one
// Gaussian at a time: the fit with N Gaussians starts (among others) from the fit with N - 1 plus
// one more Gaussian, so the error never increases with N. Everything is deterministic.
#include "approx/models.h"

#include <Eigen/LU>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace ssslab::approx {

namespace {

constexpr int kMaxCoarse = 192;  // coarse cells per side of the quadrant
constexpr int kMaxGaussians = 6;

size_t at(int i) {
    return static_cast<size_t>(i);
}

// Mass of the unit-integral 1D Gaussian of standard deviation `sigma` over [x0, x1], 0 <= x0 <
// x1: erf differences near the centre, erfc differences in the tail (no cancellation there).
double gaussian_cell_mass(double x0, double x1, double sigma) {
    const double s = 1.0 / (sigma * std::sqrt(2.0));
    const double u0 = x0 * s, u1 = x1 * s;
    if (u0 < 0.5) return 0.5 * (std::erf(u1) - std::erf(u0));
    return 0.5 * (std::erfc(u0) - std::erfc(u1));
}

// The quadrant aggregated into blocks of b x b cells (the last block of a row may be narrower).
struct CoarseGrid {
    Eigen::MatrixXd q;          // m x m block sums
    std::vector<double> edges;  // m + 1 cell edges [mm], from 0 to n h
    double q_norm2 = 0;         // sum of q^2 over the quadrant
    int block = 1;
};

CoarseGrid coarsen(const Kernel2D& k) {
    const int n = k.n();
    CoarseGrid c;
    c.block = (n + kMaxCoarse - 1) / kMaxCoarse;
    const int b = c.block, m = (n + b - 1) / b;
    c.q = Eigen::MatrixXd::Zero(m, m);
    const Eigen::MatrixXd& q = k.quadrant();
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) c.q(i / b, j / b) += q(i, j);
    c.edges.resize(at(m + 1));
    for (int I = 0; I < m; ++I) c.edges[at(I)] = static_cast<double>(I) * b * k.h_mm();
    c.edges[at(m)] = n * k.h_mm();
    c.q_norm2 = c.q.squaredNorm();
    return c;
}

using SmallMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxGaussians + 1, kMaxGaussians + 1>;
using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxGaussians + 1, 1>;

// min_w  q2 - 2 b.w + w^T G w  subject to sum w = 1, w >= 0, for a positive semi-definite G.
// The minimiser is the equality-constrained minimiser on its support, so the best feasible one
// over all supports is the exact solution (first the full support, which is optimal whenever it
// is feasible). Returns the objective; `w` gets the weights.
double solve_weights(const SmallMatrix& G, const SmallVector& b, double q2, SmallVector& w) {
    const int N = static_cast<int>(b.size());
    const auto objective = [&](const SmallVector& v) { return q2 - 2.0 * b.dot(v) + v.dot(G * v); };
    double best = std::numeric_limits<double>::infinity();
    SmallVector cand(N);
    const unsigned full = (1u << N) - 1;
    // The full support first (k = 0), then every other non-empty support.
    for (unsigned k = 0; k < full; ++k) {
        const unsigned mask = k == 0 ? full : k;
        int idx[kMaxGaussians];
        int s = 0;
        for (int i = 0; i < N; ++i)
            if (mask & (1u << i)) idx[s++] = i;
        // KKT system [G_SS 1; 1^T 0] [w_S; -lambda] = [b_S; 1].
        SmallMatrix A(s + 1, s + 1);
        SmallVector rhs(s + 1);
        for (int r = 0; r < s; ++r) {
            for (int c = 0; c < s; ++c) A(r, c) = G(idx[r], idx[c]);
            A(r, s) = 1.0;
            A(s, r) = 1.0;
            rhs(r) = b(idx[r]);
        }
        A(s, s) = 0.0;
        rhs(s) = 1.0;
        const Eigen::FullPivLU<SmallMatrix> lu(A);
        if (!lu.isInvertible()) continue;  // a smaller support reaches the same minimum
        const SmallVector sol = lu.solve(rhs);
        bool feasible = true;
        cand.setZero();
        for (int r = 0; r < s; ++r) {
            if (!(sol(r) >= 0)) feasible = false;
            cand(idx[r]) = sol(r);
        }
        if (!feasible) continue;
        const double f = objective(cand);
        if (f < best) {
            best = f;
            w = cand;
            if (mask == full) return best;  // feasible on the full support: optimal
        }
    }
    if (!std::isfinite(best)) {
        // Only reachable with a degenerate G: fall back to the best single Gaussian.
        for (int i = 0; i < N; ++i) {
            cand.setZero();
            cand(i) = 1.0;
            const double f = objective(cand);
            if (f < best) {
                best = f;
                w = cand;
            }
        }
    }
    return best;
}

// The objective for log-variances x: the squared L2 error over the full coarse grid (4 times the
// quadrant's), with the optimal weights.
class MixtureObjective {
  public:
    MixtureObjective(const CoarseGrid& c, double log_min, double log_max)
        : c_(c), log_min_(log_min), log_max_(log_max) {}

    double clamp(double x) const { return std::clamp(x, log_min_, log_max_); }

    double operator()(const std::vector<double>& x, SmallVector* weights = nullptr) {
        ++evaluations;
        const int N = static_cast<int>(x.size());
        const int m = static_cast<int>(c_.q.rows());
        C_.resize(m, N);
        for (int i = 0; i < N; ++i) {
            const double sigma = std::exp(0.5 * clamp(x[at(i)]));
            for (int I = 0; I < m; ++I)
                C_(I, i) = gaussian_cell_mass(c_.edges[at(I)], c_.edges[at(I + 1)], sigma);
        }
        QC_.noalias() = c_.q * C_;
        SmallMatrix G(N, N);
        SmallVector b(N);
        for (int i = 0; i < N; ++i) {
            b(i) = C_.col(i).dot(QC_.col(i));
            for (int j = 0; j <= i; ++j) {
                const double d = C_.col(i).dot(C_.col(j));
                G(i, j) = G(j, i) = d * d;
            }
        }
        SmallVector w(N);
        const double f = solve_weights(G, b, c_.q_norm2, w);
        if (weights) *weights = w;
        return 4.0 * std::max(0.0, f);
    }

    long evaluations = 0;

  private:
    const CoarseGrid& c_;
    double log_min_, log_max_;
    Eigen::MatrixXd C_, QC_;
};

struct Minimum {
    std::vector<double> x;
    double f = std::numeric_limits<double>::infinity();
};

// Nelder-Mead (standard coefficients 1, 2, 1/2, 1/2) from x0 with an axis-aligned initial simplex
// of size `step`. Stops when the simplex is tiny, or small with (relatively) equal values.
Minimum nelder_mead(const std::function<double(const std::vector<double>&)>& f,
                    const std::vector<double>& x0, double step, int max_evals) {
    const int d = static_cast<int>(x0.size());
    std::vector<std::vector<double>> p(at(d + 1), x0);
    std::vector<double> v(at(d + 1));
    for (int i = 0; i < d; ++i) p[at(i + 1)][at(i)] += step;
    int evals = 0;
    for (int i = 0; i <= d; ++i) {
        v[at(i)] = f(p[at(i)]);
        ++evals;
    }
    std::vector<int> order(at(d + 1));
    std::vector<double> centroid(at(d)), xr(at(d)), xe(at(d)), xc(at(d));
    const auto affine = [&](double a, const std::vector<double>& u, double bb,
                            const std::vector<double>& w, std::vector<double>& out) {
        for (int i = 0; i < d; ++i) out[at(i)] = a * u[at(i)] + bb * w[at(i)];
    };
    while (true) {
        std::iota(order.begin(), order.end(), 0);
        std::stable_sort(order.begin(), order.end(),
                         [&](int a, int b) { return v[at(a)] < v[at(b)]; });
        const int best = order[0], worst = order[at(d)], second = order[at(d - 1)];
        double diam = 0;
        for (int i = 0; i <= d; ++i)
            for (int j = 0; j < d; ++j)
                diam = std::max(diam, std::fabs(p[at(i)][at(j)] - p[at(best)][at(j)]));
        const double frange = v[at(worst)] - v[at(best)];
        if (diam < 1e-8 || (diam < 1e-3 && frange <= 1e-13 * std::fabs(v[at(best)])) ||
            evals >= max_evals)
            break;
        std::fill(centroid.begin(), centroid.end(), 0.0);
        for (int k = 0; k < d; ++k)
            for (int j = 0; j < d; ++j) centroid[at(j)] += p[at(order[at(k)])][at(j)] / d;
        affine(2.0, centroid, -1.0, p[at(worst)], xr);  // reflection
        const double fr = f(xr);
        ++evals;
        if (fr < v[at(best)]) {
            affine(3.0, centroid, -2.0, p[at(worst)], xe);  // expansion
            const double fe = f(xe);
            ++evals;
            if (fe < fr) {
                p[at(worst)] = xe;
                v[at(worst)] = fe;
            } else {
                p[at(worst)] = xr;
                v[at(worst)] = fr;
            }
            continue;
        }
        if (fr < v[at(second)]) {
            p[at(worst)] = xr;
            v[at(worst)] = fr;
            continue;
        }
        if (fr < v[at(worst)]) {
            affine(0.5, centroid, 0.5, xr, xc);  // outside contraction
            const double fc = f(xc);
            ++evals;
            if (fc <= fr) {
                p[at(worst)] = xc;
                v[at(worst)] = fc;
                continue;
            }
        } else {
            affine(0.5, centroid, 0.5, p[at(worst)], xc);  // inside contraction
            const double fc = f(xc);
            ++evals;
            if (fc < v[at(worst)]) {
                p[at(worst)] = xc;
                v[at(worst)] = fc;
                continue;
            }
        }
        for (int i = 0; i <= d; ++i) {  // shrink towards the best vertex
            if (i == best) continue;
            affine(0.5, p[at(best)], 0.5, p[at(i)], p[at(i)]);
            v[at(i)] = f(p[at(i)]);
            ++evals;
        }
    }
    Minimum r;
    const auto it = std::min_element(v.begin(), v.end());
    r.x = p[at(static_cast<int>(it - v.begin()))];
    r.f = *it;
    return r;
}

// Nelder-Mead from x0, restarted from its result with smaller simplices while that helps.
Minimum search(MixtureObjective& obj, const std::vector<double>& x0) {
    const int d = static_cast<int>(x0.size());
    const auto f = [&](const std::vector<double>& x) { return obj(x); };
    const int max_evals = 300 + 200 * d * d;
    Minimum best = nelder_mead(f, x0, 1.0, max_evals);
    double step = 0.25;
    for (int restart = 0; restart < 3; ++restart, step *= 0.25) {
        const Minimum r = nelder_mead(f, best.x, step, max_evals);
        const bool better = r.f < best.f;
        const double gain = best.f - r.f;
        if (better) best = r;
        if (!better || gain <= 1e-10 * best.f) break;
    }
    return best;
}

struct Fit {
    std::vector<double> weights, variances;
    double l2_error = 0;
    long evaluations = 0;
    int coarse_cells = 0;
};

Fit fit(const Kernel2D& k, int count) {
    if (count < 1 || count > kMaxGaussians)
        throw std::invalid_argument("fit_gaussian_mixture: N = " + std::to_string(count) +
                                    " is outside [1, " + std::to_string(kMaxGaussians) + "]");
    const CoarseGrid c = coarsen(k);
    const double h = k.h_mm(), extent = k.n() * h;
    // Starting variances span (h/2)^2 .. (extent/2)^2; the search may go 1e3 beyond either end.
    const double lo = 2.0 * std::log(0.5 * h), hi = 2.0 * std::log(0.5 * extent);
    MixtureObjective obj(c, lo - std::log(1e3), hi + std::log(1e3));

    Minimum prev;
    for (int N = 1; N <= count; ++N) {
        std::vector<std::vector<double>> starts;
        // A geometric spacing over the whole range (for N = 1: the quartiles in log space).
        if (N == 1) {
            for (double t : {0.25, 0.5, 0.75}) starts.push_back({lo + t * (hi - lo)});
        } else {
            std::vector<double> g(at(N));
            for (int i = 0; i < N; ++i) g[at(i)] = lo + (hi - lo) * i / (N - 1);
            starts.push_back(g);
            // The previous fit plus one Gaussian: below, above, and in its widest gap.
            std::vector<double> x = prev.x;
            std::sort(x.begin(), x.end());
            auto with = [&](double extra) {
                std::vector<double> s = x;
                s.push_back(obj.clamp(extra));
                return s;
            };
            starts.push_back(with(x.front() - 2.0));
            starts.push_back(with(x.back() + 2.0));
            int gap = -1;
            for (int i = 0; i + 1 < N - 1; ++i)
                if (gap < 0 || x[at(i + 1)] - x[at(i)] > x[at(gap + 1)] - x[at(gap)]) gap = i;
            if (gap >= 0) starts.push_back(with(0.5 * (x[at(gap)] + x[at(gap + 1)])));
        }
        Minimum best;
        for (const auto& s : starts) {
            Minimum r = search(obj, s);
            if (r.f < best.f) best = std::move(r);
        }
        // The previous fit with a zero-weight extra Gaussian is feasible: never worse than it.
        prev = std::move(best);
    }

    for (double& x : prev.x) x = obj.clamp(x);
    SmallVector w;
    obj(prev.x, &w);
    std::vector<int> order(at(count));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return prev.x[at(a)] < prev.x[at(b)]; });
    Fit r;
    for (int i : order) {
        r.variances.push_back(std::exp(prev.x[at(i)]));
        r.weights.push_back(w(i));
    }
    // The error of the result, from the residual itself (not the expanded quadratic form).
    const int m = static_cast<int>(c.q.rows());
    Eigen::MatrixXd res = c.q;
    for (int i = 0; i < count; ++i) {
        Eigen::VectorXd g(m);
        const double sigma = std::sqrt(r.variances[at(i)]);
        for (int I = 0; I < m; ++I)
            g(I) = gaussian_cell_mass(c.edges[at(I)], c.edges[at(I + 1)], sigma);
        res.noalias() -= r.weights[at(i)] * g * g.transpose();
    }
    r.l2_error = std::sqrt(4.0 * res.squaredNorm());
    r.evaluations = obj.evaluations;
    r.coarse_cells = m;
    return r;
}

}  // namespace

GaussianMixture fit_gaussian_mixture(const Kernel2D& k, int count) {
    Fit f = fit(k, count);
    return GaussianMixture{std::move(f.weights), std::move(f.variances)};
}

ModelResult sum_of_gaussians(const Kernel2D& k, int count) {
    const auto t0 = std::chrono::steady_clock::now();
    const Fit f = fit(k, count);
    ModelResult r;
    r.kernel.model = "deon" + std::to_string(count);
    r.kernel.h_mm = k.h_mm();
    r.kernel.n = k.n();
    const int n = k.n();
    const double h = k.h_mm();
    for (int i = 0; i < count; ++i) {
        SeparableTerm t;
        t.a.resize(at(n));
        const double s = std::sqrt(f.weights[at(i)]), sigma = std::sqrt(f.variances[at(i)]);
        for (int j = 0; j < n; ++j) t.a[at(j)] = s * gaussian_cell_mass(j * h, (j + 1) * h, sigma);
        r.kernel.terms.push_back(std::move(t));
        r.info["weight_" + std::to_string(i + 1)] = f.weights[at(i)];
        r.info["variance_" + std::to_string(i + 1)] = f.variances[at(i)];
    }
    r.info["l2_error"] = f.l2_error;
    // Every term is non-negative, so the L1 norm is the sum (4 (sum a)^2 per term): no n x n sum.
    r.info["l1"] = r.kernel.sum();
    r.info["evaluations"] = static_cast<double>(f.evaluations);
    r.info["coarse_cells"] = f.coarse_cells;
    r.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace ssslab::approx
