// Separable (sum of rank-1) approximations of a Kernel2D, the common output of every model:
// A(x, y) = sum_k sign_k a_k(x) a_k(y). Every a_k is even; it is stored for x >= 0 at the cell
// centres of the kernel grid, (i + 1/2) h, i in [0, n), as cell masses.
#pragma once

#include "approx/kernel2d.h"

#include <map>
#include <string>
#include <vector>

namespace ssslab::approx {

struct SeparableTerm {
    std::vector<double> a;  ///< half of the even 1D kernel: a[i] at x = +-(i + 1/2) h
    double sign = 1.0;      ///< +1 or -1 (an SVD term of a negative eigenvalue)
};

struct SeparableKernel {
    std::string model;
    double h_mm = 0;
    int n = 0;
    std::vector<SeparableTerm> terms;

    int rank() const { return static_cast<int>(terms.size()); }
    /// Each rank-1 term costs a horizontal and a vertical pass.
    int convolutions_1d() const { return 2 * rank(); }
    /// A(x, y) at full-grid cells x, y in [-n, n).
    double at(int x, int y) const;
    /// The quadrant of A (n x n).
    Eigen::MatrixXd quadrant() const;
    /// sum over the full grid of A and of |A|.
    double sum() const;
    double l1() const;
    /// Multiply A by f (every a_k by sqrt(f)).
    void scale(double f);
};

/// A model's result for one channel, with what it cost and how well its constraints hold.
struct ModelResult {
    SeparableKernel kernel;
    double build_seconds = 0;
    std::map<std::string, double> info;  ///< e.g. constraint_error, iterations, sigma_1
};

/// Kernel-space comparison of an approximation with the kernel it approximates (both on the same
/// grid; the kernel has unit L1).
struct KernelErrors {
    double rms = 0;               ///< sqrt(mean over the 2n x 2n cells of (K - A)^2)
    double max_abs = 0;           ///< max |K - A|
    double l1_error = 0;          ///< |sum A - sum K| (energy)
    double radial_asymmetry = 0;  ///< RMS over radii of A along the axis minus A along the
                                  ///< diagonal, relative to K's RMS along the axis
};
KernelErrors kernel_errors(const Kernel2D& k, const SeparableKernel& a);

}  // namespace ssslab::approx
