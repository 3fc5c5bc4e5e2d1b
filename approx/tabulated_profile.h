// A profile known at radii only: what a model evaluated elsewhere (a .bssrdf file's GLSL through
// the GL twin, realtime/gl/bssrdf_gl.h) hands to the scoring, which needs R_d at any r
// (DiffusionProfile::annulus_mean integrates adaptively) and R_dr.
#pragma once

#include "approx/diffusion.h"

#include <string>
#include <vector>

namespace ssslab::approx {

/// R_d tabulated at n radii spaced evenly in ln r, r_k = r_min (r_max / r_min)^{k/(n-1)}, and
/// interpolated by cubic Hermite (Catmull-Rom) in (ln r, ln R_d) where the four values around r
/// are positive (error O(h^3) in the log spacing h: below 1e-7 relative for the dipole's
/// e^{-sigma_tr r} out to sigma_tr r = 100 at 2048 radii a decade), linearly in R_d where one is
/// not (a table's zeros, a model's sign change); R_d(r_min) below r_min, 0 beyond r_max.
/// R_dr = pi r_min^2 R_d(r_min) + 2 pi int_{r_min}^{r_max} R_d r dr over the interpolant (adaptive
/// Gauss-Kronrod in ln r, to max(1e-10, accuracy)). `accuracy` is the values' own relative
/// accuracy (rd_accuracy(): 1e-6 for float evaluations), below which integrals of the profile are
/// not refined: the interpolant is only C1 at its nodes, and an adaptive quadrature asked for
/// 1e-10 subdivides down to the node spacing (measured: the sphere study's M(beta) of a GL
/// table took 25 s at 1e-10, 0.25 s at 1e-7).
class TabulatedProfile final : public DiffusionProfile {
  public:
    /// The radii of a table: n >= 4, 0 < r_min < r_max.
    static std::vector<double> radii(double r_min, double r_max, int n);
    /// `values` at radii(r_min, r_max, values.size()); every value finite (std::invalid_argument
    /// naming the model and the radius otherwise).
    TabulatedProfile(std::string name, const DiffusionMedium& m, double r_min, double r_max,
                     std::vector<double> values, bool single_scattering, double accuracy = 0);

    std::string name() const override { return name_; }
    double total_rd() const override { return total_; }
    bool includes_single_scattering() const override { return single_; }
    double rd_accuracy() const override { return accuracy_; }

  private:
    double eval_rd(double r) const override;

    std::string name_;
    double ln_min_, ln_max_, h_;
    std::vector<double> v_, ln_v_;  ///< ln_v_: ln of the value, NaN where it is not positive
    bool single_;
    double accuracy_;
    double total_ = 0;
};

}  // namespace ssslab::approx
