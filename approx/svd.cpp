#include "approx/models.h"

#include <Spectra/SymEigsSolver.h>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace ssslab::approx {

namespace {

// y = E x for the even block E = 2 q of the kernel matrix: in the orthonormal basis
// (e_i + e_{-i-1}) / sqrt(2) of even vectors, K acts as 2 q; on odd vectors it is zero.
class EvenBlockOp {
  public:
    using Scalar = double;
    explicit EvenBlockOp(const Eigen::MatrixXd& q) : q_(q) {}
    Eigen::Index rows() const { return q_.rows(); }
    Eigen::Index cols() const { return q_.cols(); }
    void perform_op(const double* x, double* y) const {
        Eigen::Map<const Eigen::VectorXd> xin(x, q_.rows());
        Eigen::Map<Eigen::VectorXd> yout(y, q_.rows());
        yout.noalias() = q_ * xin;
        yout *= 2.0;
    }

  private:
    const Eigen::MatrixXd& q_;
};

struct EigenPairs {
    Eigen::VectorXd values;   // by decreasing magnitude
    Eigen::MatrixXd vectors;  // unit vectors of the even block
    int iterations = 0;
};

EigenPairs leading_eigenpairs(const Eigen::MatrixXd& q, int count) {
    const int n = static_cast<int>(q.rows());
    if (count < 1) throw std::invalid_argument("SVD: rank < 1");
    count = std::min(count, n);
    EigenPairs r;
    if (n <= 256 || count * 2 + 1 >= n) {
        // Small: a full symmetric eigendecomposition of the n x n block is cheap and exact.
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(2.0 * q);
        std::vector<int> idx(static_cast<size_t>(n));
        for (int i = 0; i < n; ++i) idx[static_cast<size_t>(i)] = i;
        std::sort(idx.begin(), idx.end(), [&](int a, int b) {
            return std::fabs(es.eigenvalues()(a)) > std::fabs(es.eigenvalues()(b));
        });
        r.values.resize(count);
        r.vectors.resize(n, count);
        for (int k = 0; k < count; ++k) {
            r.values(k) = es.eigenvalues()(idx[static_cast<size_t>(k)]);
            r.vectors.col(k) = es.eigenvectors().col(idx[static_cast<size_t>(k)]);
        }
        return r;
    }
    EvenBlockOp op(q);
    const int ncv = std::min(n, std::max(2 * count + 1, 20));
    Spectra::SymEigsSolver<EvenBlockOp> eigs(op, count, ncv);
    eigs.init();
    eigs.compute(Spectra::SortRule::LargestMagn, 10000, 1e-12, Spectra::SortRule::LargestMagn);
    if (eigs.info() != Spectra::CompInfo::Successful)
        throw std::runtime_error("SVD: the Lanczos iteration did not converge");
    r.values = eigs.eigenvalues();
    r.vectors = eigs.eigenvectors();
    r.iterations = static_cast<int>(eigs.num_iterations());
    return r;
}

}  // namespace

std::vector<double> singular_values(const Kernel2D& k, int count) {
    const EigenPairs e = leading_eigenpairs(k.quadrant(), count);
    std::vector<double> s;
    for (int i = 0; i < e.values.size(); ++i) s.push_back(std::fabs(e.values(i)));
    return s;
}

ModelResult svd_rank_n(const Kernel2D& k, int rank, bool renormalize) {
    const auto t0 = std::chrono::steady_clock::now();
    const EigenPairs e = leading_eigenpairs(k.quadrant(), rank);
    ModelResult r;
    r.kernel.model = "svd" + std::to_string(rank) + (renormalize ? "-l1" : "");
    r.kernel.h_mm = k.h_mm();
    r.kernel.n = k.n();
    for (int i = 0; i < e.values.size(); ++i) {
        SeparableTerm t;
        const double s = std::sqrt(std::fabs(e.values(i)));
        // Full-grid unit vector u(x) = v(|x|) / sqrt(2); a = sqrt(|lambda|) u, sign of lambda.
        // The sign of a singular vector is arbitrary: make the term's sum non-negative.
        const double flip = e.vectors.col(i).sum() < 0 ? -1.0 : 1.0;
        t.a.resize(static_cast<size_t>(k.n()));
        for (int j = 0; j < k.n(); ++j)
            t.a[static_cast<size_t>(j)] = flip * s * e.vectors(j, i) / std::sqrt(2.0);
        t.sign = e.values(i) < 0 ? -1.0 : 1.0;
        r.kernel.terms.push_back(std::move(t));
        r.info["sigma_" + std::to_string(i + 1)] = std::fabs(e.values(i));
    }
    const double l1 = r.kernel.l1();
    r.info["l1"] = l1;
    r.info["iterations"] = e.iterations;
    if (renormalize && l1 > 0) r.kernel.scale(1.0 / l1);
    r.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

ModelResult preintegration(const Kernel2D& k) {
    const auto t0 = std::chrono::steady_clock::now();
    ModelResult r;
    r.kernel.model = "preintegration";
    r.kernel.h_mm = k.h_mm();
    r.kernel.n = k.n();
    SeparableTerm t;
    // a_p(x) = sum over all y of K(x, y) = 2 sum_j q(i, j); ||K||_1 = 1, so a = a_p (Eq. 5.18).
    const Eigen::VectorXd rows = 2.0 * k.quadrant().rowwise().sum();
    t.a.assign(rows.data(), rows.data() + rows.size());
    r.kernel.terms.push_back(std::move(t));
    r.info["l1_error"] = std::fabs(r.kernel.sum() - 1.0);
    r.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace ssslab::approx
