// The discrete 2D kernel of a radial diffuse reflectance profile [Freude14 §6.1, "simple
// rotation"], the input of every separable kernel model.
//
// Grid: square cells of side h centred on the origin, 2n cells per side, cell centres at
// ((i + 1/2) h, (j + 1/2) h) for i, j in [-n, n). There is no cell at the origin: every kernel is
// even in x and in y, so it is stored by its quadrant q(i, j) = K(|x|, |y|), i, j in [0, n).
// Cell values are masses (the profile integrated over the cell), normalised to unit L1 per channel
// as the thesis normalises its kernels; raw_l1 keeps the fraction of the diffuse reflectance the
// grid holds.
//
// The profile is MCML's: annulus averages R_k over [k dr, (k+1) dr). Inside an annulus it is
// taken as constant, and a cell's mass is the average of s x s sub-samples of that piecewise
// constant function (s chosen so that sub-samples are at most dr / 2 apart).
//
// Grid rule (KernelGrid::from_profile): h = dr and n = nr, the thesis's MCML grid (Freude14 Table
// 6.1: dr = min MFP / 20, extent 32 max MFP), optionally refined by an integer factor. Lengths in
// mm in the whole approx/ module.
#pragma once

#include "core/profile.h"

#include <Eigen/Core>

#include <string>

namespace ssslab::approx {

struct KernelGrid {
    double h_mm = 0;  ///< cell size
    int n = 0;        ///< cells per half side (2n per side)
    /// The thesis's grid for this profile (h = dr, n = nr), refined `refine` times (h / refine,
    /// n * refine): the same extent, finer cells.
    static KernelGrid from_profile(const RadialProfile& p, int refine = 1);
    double extent_mm() const { return n * h_mm; }
};

class Kernel2D {
  public:
    /// Build the kernel of channel `c` of `p` on `grid`.
    Kernel2D(const RadialProfile& p, int c, const KernelGrid& grid);
    /// A kernel from a given quadrant (for tests); normalised to unit L1.
    Kernel2D(Eigen::MatrixXd quadrant, double h_mm);

    double h_mm() const { return h_; }
    int n() const { return static_cast<int>(q_.rows()); }
    int size() const { return 2 * n(); }
    /// Quadrant q(i, j) = K at cell centres ((i+1/2) h, (j+1/2) h), i, j in [0, n).
    const Eigen::MatrixXd& quadrant() const { return q_; }
    /// Full-grid value, x, y in [-n, n) (cell x has its centre at (x + 1/2) h).
    double at(int x, int y) const { return q_(fold(x), fold(y)); }
    /// Mass of the unnormalised kernel on the grid: the part of the diffuse reflectance it holds.
    double raw_l1() const { return raw_l1_; }
    /// The full 2n x 2n matrix (for small kernels and tests).
    Eigen::MatrixXd full() const;

    static int fold(int x) { return x >= 0 ? x : -x - 1; }

  private:
    Eigen::MatrixXd q_;
    double h_ = 0;
    double raw_l1_ = 1;
};

}  // namespace ssslab::approx
