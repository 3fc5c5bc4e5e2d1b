// "three_gaussian": a rank-1 separable kernel whose 1D factor is a mixture of three Gaussians,
// a(x) = sum_i w_i G(x; sigma_i), fitted to the pre-integrated profile a_p(x) = int R_d(x, y) dy
// [Freude14 Eq. 5.17] by least squares over the kernel grid's cells. It extends the manual
// two-Gaussian model [Freude14 Eq. 5.21] by a third lobe and fits it instead of taking an
// artist's widths. Energy is held exactly: each Gaussian is normalised on the grid and the weights
// are >= 0 and sum to 1, so the kernel keeps the exact kernel's unit L1.
//
// Parameters: widths=N, the number of log-spaced candidate widths of the search (default 24).
#include "three_gaussian.h"

#include "approx/model_spec.h"
#include "approx/models.h"

#include <Eigen/Dense>

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

namespace custom {

namespace {

using ssslab::approx::Kernel2D;
using ssslab::approx::ModelContext;
using ssslab::approx::ModelResult;
using ssslab::approx::ModelSpec;

// The half vector (cells i h .. (i + 1) h, i in [0, n)) of a Gaussian of deviation sigma on k's
// grid, exact cell masses scaled to sum 1/2 (the factor of a kernel of unit L1): the manual
// model's factor with both Gaussians the same (approx/models.h).
std::vector<double> gaussian_cells(const Kernel2D& k, double sigma) {
    return ssslab::approx::manual_two_gaussian(k, sigma, sigma, 1.0).kernel.terms.at(0).a;
}

struct Fit {
    std::array<double, 3> sigma{}, w{};
    double sse = std::numeric_limits<double>::infinity();
};

// min ||sum_i w_i g_i - t||^2 subject to sum w = 1, w >= 0, for three fixed columns: the
// equality-constrained solution on every subset of the columns (the active set of a 3-variable
// problem, enumerated), keeping the best feasible one.
Fit fit_weights(const std::array<const std::vector<double>*, 3>& g, const std::vector<double>& t) {
    Eigen::Matrix3d gram = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    double tt = 0;
    for (size_t i = 0; i < t.size(); ++i) {
        for (int a = 0; a < 3; ++a) {
            rhs[a] += (*g[a])[i] * t[i];
            for (int b = a; b < 3; ++b) gram(a, b) += (*g[a])[i] * (*g[b])[i];
        }
        tt += t[i] * t[i];
    }
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < a; ++b) gram(a, b) = gram(b, a);
    Fit best;
    for (int subset = 1; subset < 8; ++subset) {
        std::vector<int> cols;
        for (int a = 0; a < 3; ++a)
            if (subset & (1 << a)) cols.push_back(a);
        const int m = static_cast<int>(cols.size());
        // KKT system [G 1; 1^T 0] [w; lambda] = [g^T t; 1].
        Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(m + 1, m + 1);
        Eigen::VectorXd b = Eigen::VectorXd::Zero(m + 1);
        for (int i = 0; i < m; ++i) {
            for (int j = 0; j < m; ++j) kkt(i, j) = gram(cols[i], cols[j]);
            kkt(i, m) = kkt(m, i) = 1.0;
            b[i] = rhs[cols[i]];
        }
        b[m] = 1.0;
        const Eigen::VectorXd x = kkt.fullPivLu().solve(b);
        Eigen::Vector3d w = Eigen::Vector3d::Zero();
        bool feasible = true;
        for (int i = 0; i < m; ++i) {
            w[cols[i]] = x[i];
            feasible = feasible && x[i] >= 0 && std::isfinite(x[i]);
        }
        if (!feasible) continue;
        const double sse = tt - 2 * w.dot(rhs) + w.dot(gram * w);
        if (sse < best.sse) {
            best.sse = sse;
            for (int a = 0; a < 3; ++a) best.w[static_cast<size_t>(a)] = w[a];
        }
    }
    return best;
}

ModelResult three_gaussian(const ModelSpec& spec, const Kernel2D& k, const ModelContext&) {
    const auto t0 = std::chrono::steady_clock::now();
    const int n = k.n();
    const double h = k.h_mm();
    // The target: the pre-integrated profile, the exact kernel's marginal.
    const std::vector<double> target = ssslab::approx::preintegration(k).kernel.terms.at(0).a;

    // A log-spaced search over width triples sigma_1 < sigma_2 < sigma_3 in [h / 4, n h] ...
    const int count = static_cast<int>(spec.number("widths", 24));
    const double lo = std::log(0.25 * h), hi = std::log(n * h);
    std::vector<double> sigmas;
    std::vector<std::vector<double>> cells;
    for (int i = 0; i < count; ++i) {
        sigmas.push_back(std::exp(lo + (hi - lo) * i / (count - 1)));
        cells.push_back(gaussian_cells(k, sigmas.back()));
    }
    Fit best;
    for (int a = 0; a < count; ++a)
        for (int b = a + 1; b < count; ++b)
            for (int c = b + 1; c < count; ++c) {
                Fit f = fit_weights({&cells[a], &cells[b], &cells[c]}, target);
                if (f.sse < best.sse) {
                    f.sigma = {sigmas[a], sigmas[b], sigmas[c]};
                    best = f;
                }
            }
    // ... refined one width at a time by factors exp(+-step), the step halved each round.
    double step = (hi - lo) / (count - 1);
    std::array<std::vector<double>, 3> g;
    for (int i = 0; i < 3; ++i) g[i] = gaussian_cells(k, best.sigma[i]);
    for (int round = 0; round < 12; ++round, step *= 0.5)
        for (int i = 0; i < 3; ++i)
            for (const double dir : {-1.0, 1.0}) {
                const double s = best.sigma[i] * std::exp(dir * step);
                std::array<std::vector<double>, 3> trial = g;
                trial[i] = gaussian_cells(k, s);
                Fit f = fit_weights({&trial[0], &trial[1], &trial[2]}, target);
                if (f.sse < best.sse) {
                    f.sigma = best.sigma;
                    f.sigma[i] = s;
                    best = f;
                    g = std::move(trial);
                }
            }

    ModelResult r;
    r.kernel.h_mm = h;
    r.kernel.n = n;
    ssslab::approx::SeparableTerm term;
    term.a.assign(static_cast<size_t>(n), 0.0);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < n; ++j) term.a[j] += best.w[i] * g[i][j];
    r.kernel.terms.push_back(std::move(term));
    for (int i = 0; i < 3; ++i) {
        r.info["sigma_" + std::to_string(i + 1) + "_mm"] = best.sigma[i];
        r.info["w_" + std::to_string(i + 1)] = best.w[i];
    }
    r.info["fit_rms"] = std::sqrt(std::max(0.0, best.sse) / n);
    r.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace

void register_three_gaussian() {
    ssslab::approx::ModelFactory f;
    f.name = "three_gaussian";
    f.keys = {"widths"};
    f.help = "three_gaussian[:widths=N] (examples/custom_model: three Gaussians fitted to a_p)";
    f.version = "three-gaussian-1";
    f.closed_form = [](const ModelSpec&) { return false; };
    f.validate = [](const ModelSpec& m) {
        const double w = m.number("widths", 24);
        if (w < 3 || w > 64 || w != std::floor(w))
            throw std::invalid_argument("model \"" + m.text +
                                        "\": widths must be an integer in [3, 64]");
    };
    f.build = three_gaussian;
    ssslab::approx::register_model(std::move(f));
}

}  // namespace custom
