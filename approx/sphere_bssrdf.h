// An analytic radial profile R_d integrated over a sphere lit by a directional light
// [Bitterli13 §3.5 "BSSRDF Integration on the Sphere"]: the radiant exitance M(beta) that a
// renderer using R_d as a BSSRDF predicts on a sphere, to compare with the light-tracing ground
// truth of volpath/sphere.h (which is kept out of this module: approx depends on core only, so
// the camera convention of volpath::sphere_camera is replicated below and `ssslab sphere` checks
// that the two agree).
//
// Scene (as volpath::SphereScene): a sphere of radius R, centred at the origin; a directional
// light of irradiance E0 = 1 (per unit area perpendicular to it), l the unit vector towards it. The
// irradiance transmitted into the surface at a point x_i with normal n_i is
//   E_t(x_i) = E0 max(0, n_i . l) T(n_i . l),
// and the exitance predicted at x_o is
//   M(x_o) = int_sphere R_d(|x_o - x_i|) E_t(x_i) dA_i            [Bitterli13 Eq. 2.14].
// The distance plugged into the profile is the *chord* |x_o - x_i| (what a renderer that samples
// the BSSRDF on the surface computes), not the geodesic distance.
//
// Entry weight T (EntryWeight):
//  - kFresnel: T = 1 - F(mu, eta) for a profile per unit power *entering* the medium (every
//    model of approx/diffusion.h: includes_entry_fresnel() is false), and
//    T = (1 - F(mu, eta)) / (1 - F(1, eta)) for a profile that already carries the entry factor
//    at normal incidence (includes_entry_fresnel()), so that the normal-incidence factor is not
//    applied twice. F is the unpolarised Fresnel reflectance of the smooth boundary for light
//    arriving from outside (relative index eta = n_medium / n_outside). This is what the path
//    tracer does (volpath: weight 1 - F on entry), so it is the like-for-like comparison.
//  - kCosineOnly: T = 1, the irradiance E0 max(0, n . l) alone (a renderer that ignores the
//    entry Fresnel factor).
//
// Quadrature. By axisymmetry about l, M depends only on beta, the angle between n_o and l. In
// coordinates centred on x_o (polar angle psi from n_o, azimuth phi about it), n_i . l =
// cos psi cos beta + sin psi sin beta cos phi, the chord is r = 2 R sin(psi / 2) and
// dA = R^2 sin psi dpsi dphi = r dr dphi exactly (d(r^2) = 2 R^2 sin psi dpsi), so
//   M(beta) = int_0^2R 2 pi r R_d(r) G(psi(r), beta) dr,
//   G(psi, beta) = (1 / 2 pi) int_0^2pi E_t(cos psi cos beta + sin psi sin beta cos phi) dphi.
// G is computed in closed form for T = 1 ((a phi0 + b sin phi0) / pi, phi0 = acos(-a / b),
// a = cos psi cos beta, b = sin psi sin beta). Otherwise, when the whole circle is lit, by the
// 18-point Gauss-Chebyshev rule in cos phi (checked against the 6-point rule it contains), and
// where that check fails or the circle crosses the terminator, by adaptive Gauss-Kronrod over
// phi in [0, phi0] (phi0 where the entry cosine reaches 0, or the critical angle for eta < 1;
// to 1e-13).
// The outer integral is split at psi = pi / 2. Below, it is taken in s = ln r, integrand
// 2 pi r^2 R_d(r) G, which resolves the peak of R_d at r -> 0 (R_d ~ 1/r or ~log r for pbd and
// burley: r^2 R_d -> 0) over r in [r0, sqrt(2) R], r0 = 1e-15 2R (the disc r < r0 is left out:
// at most 2 pi int_0^r0 r R_d dr E_t, 4e-15 pi c R for R_d ~ c / r). Above, it is taken in psi,
// integrand 2 pi R^2 sin psi R_d(2 R sin(psi / 2)) G, in which r(psi) is smooth up to the
// antipode psi = pi.
//
// R_d is evaluated only to build the radial weight of the two parts (2 pi r^2 R_d in s,
// 2 pi R^2 sin psi R_d in psi) once per table: a piecewise Chebyshev interpolant (17 Lobatto
// points per panel, from panels of unit width in s and pi/32 in psi, halved until the last three
// coefficients are below rel_tol / 10 of the panel's largest value, or of 1e-30 times the
// weight's peak if that is larger: relative accuracy panel by panel, so that the profile's far
// tail, which lights the unlit pole, is as accurate as its peak).
// This costs a few thousand profile evaluations, whatever the number of beta nodes (pbd's are
// ~40 us each). Every M(beta) node is then an adaptive Gauss-Kronrod (7/15) integral of the
// interpolated weight times G, started from panels of width <= 2 in s and pi/16 in psi plus
// breakpoints where G has kinks (the circle of entry points psi = const touches the terminator
// n_i . l = 0, or for eta < 1 the critical angle), so that no narrow profile is missed, and
// refined until the estimated error is below rel_tol of the node's value.
//
// Bins. As volpath's SphereRun::exitance, bin j covers beta in [j, j + 1] pi / bins and its
// value is the zone-area average of M, (int M d(cos beta)) / (cos b0 - cos b1), by
// `nodes_per_bin`-point Gauss-Legendre in cos beta (exact for M polynomial in cos beta of
// degree < 2 nodes_per_bin). Point values M(beta) at the same nodes (plus beta = 0 and pi) form
// the table that images interpolate.
//
// Precision: double throughout. With the defaults every node is integrated to 1e-10 of its
// value (the |K15 - G7| estimate is pessimistic) on an interpolant good to ~1e-11;
// `max_rel_error` and `fit_error` report the achieved estimates. Measured (tests): the bins of
// dipole, better-dipole and pbd on Skin1 spheres of 1 and 5 mm agree with rel_tol = 1e-13 and
// 8 nodes per bin to 3e-13 (dipoles) and 2e-8 (pbd), and the point values with an independent
// brute-force quadrature to 2e-10. Interpolated values (at()) are good to ~1e-5 with 180 bins.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>
#include "core/enum_names.h"

namespace ssslab::approx {

class DiffusionProfile;

/// A radial profile R_d(r) [1/L^2] at r > 0 [L]; must be finite for r > 0 and callable from
/// several threads at once.
using RadialFunction = std::function<double(double r)>;

/// The entry weight T of the transmitted irradiance (see the file comment).
enum class EntryWeight {
    kFresnel,     ///< T = 1 - F(mu, eta), or that over 1 - F(1, eta) for entry-Fresnel profiles
    kCosineOnly,  ///< T = 1
};
const char* to_string(EntryWeight w);
}  // namespace ssslab::approx
template <>
struct ssslab::EnumNames<ssslab::approx::EntryWeight> {
    using E = ssslab::approx::EntryWeight;
    static constexpr std::array<std::pair<E, std::string_view>, 2> table = {
        {{E::kFresnel, "fresnel"}, {E::kCosineOnly, "cosine"}}};
};
namespace ssslab::approx {

/// Unpolarised Fresnel reflectance of a smooth dielectric boundary for light arriving from the
/// outside at cos theta_i = mu in [0, 1]; eta = n_inside / n_outside > 0. 1 beyond the critical
/// angle (eta < 1), 0 for eta = 1.
double dielectric_reflectance(double mu, double eta);

/// How the sphere integral is taken.
///
/// | field                  | unit | default  | meaning                                          |
/// |------------------------|------|----------|--------------------------------------------------|
/// | radius                 | L    | 1        | sphere radius R (same unit as the profile's r)   |
/// | eta                    | -    | 1        | n_medium / n_outside, for the entry Fresnel      |
/// | entry                  | -    | kFresnel | entry weight T                                   |
/// | profile_entry_fresnel  | -    | false    | the profile carries 1 - F(1) already             |
/// | beta_bins              | -    | 180      | equal-width bins of beta in [0, pi]              |
/// | nodes_per_bin          | -    | 4        | Gauss-Legendre nodes in cos beta per bin, 1..16  |
/// | rel_tol                | -    | 1e-10    | relative tolerance of each M(beta) node          |
/// | max_panels             | -    | 4000     | adaptive panels per M(beta) node at most         |
/// | threads                | -    | 0        | 0: the caller's TBB arena; > 0: that many        |
struct SphereIntegration {
    double radius = 1;
    double eta = 1;
    EntryWeight entry = EntryWeight::kFresnel;
    bool profile_entry_fresnel = false;
    int beta_bins = 180;
    int nodes_per_bin = 4;
    double rel_tol = 1e-10;
    int max_panels = 4000;
    int threads = 0;
};

/// Throws std::invalid_argument naming the field unless radius and eta are finite and > 0,
/// beta_bins in [1, 1e6], nodes_per_bin in [1, 16], rel_tol in [1e-15, 1e-2], max_panels >= 16,
/// threads >= 0.
void validate(const SphereIntegration& o);

/// The entry weight E_t / E0 at cos theta_i = mu (0 for mu <= 0).
double transmitted_irradiance(double mu, const SphereIntegration& o);

/// M(beta) / E0 [-] at one angle beta in [0, pi] [rad] (a point value), and the estimated
/// absolute error of the adaptive rule through `error` (if not null). Throws
/// std::invalid_argument for beta outside [0, pi] or invalid options. Builds the profile's
/// interpolant on every call: for many angles, integrate_sphere.
double sphere_exitance_at(const RadialFunction& rd, double beta, const SphereIntegration& o,
                          double* error = nullptr);

/// M(beta) over the sphere: bin averages (as volpath's SphereRun::exitance) and point values.
struct SphereExitance {
    SphereIntegration options;
    /// Zone-area average of M / E0 per beta bin (bin j covers [j, j + 1] pi / beta_bins) [-].
    std::vector<double> bin_mean;
    /// Point values: M / E0 at node_beta [rad], increasing from 0 to pi (the Gauss-Legendre
    /// nodes of the bins, plus both poles).
    std::vector<double> node_beta, node_value;
    /// Slopes dM/dbeta at the nodes for the interpolation in at(): Fritsch-Carlson (with
    /// Brodlie's weights) in the interior, 0 at the poles (M is even in beta about both).
    std::vector<double> node_slope;
    /// Largest estimated error of a node relative to its value (nodes with M > 0) [-].
    double max_rel_error = 0;
    /// Largest trailing Chebyshev coefficient of the profile's interpolant relative to its
    /// panel's largest value [-].
    double fit_error = 0;
    /// Profile evaluations (R_d calls) and integrand evaluations (interpolant times G) in all.
    std::uint64_t evaluations = 0, integrand_evaluations = 0;
    double seconds = 0;  ///< wall time of integrate_sphere

    /// Lower edge of bin j [rad] (j = beta_bins: pi), as SphereRun::beta_edge.
    double beta_edge(int j) const;
    /// M / E0 at beta [rad] by monotone cubic (Fritsch-Carlson) interpolation of the nodes.
    double at(double beta) const;
    /// Power leaving the sphere over the incident power pi R^2 E0 [-] (the zone-weighted sum of
    /// the bins, 2 sum_j bin_mean[j] (cos b_j - cos b_j+1)): comparable to SphereRun::diffuse.
    double total_fraction() const;
};

/// Tabulate M(beta) for a profile (nodes in parallel; deterministic for any thread count).
SphereExitance integrate_sphere(const RadialFunction& rd, const SphereIntegration& o);

/// The same for an analytic diffusion profile whose length unit is that of o.radius: eta and
/// profile_entry_fresnel are taken from the profile (medium().eta, includes_entry_fresnel()).
SphereExitance integrate_sphere(const DiffusionProfile& profile, SphereIntegration o);

/// An orthographic view of the sphere, in the convention of volpath::sphere_camera (volpath's
/// SphereScene fields of the same names): v = to_camera normalised; up = the given vector or,
/// when zero, +y (or -sign(v_y) z when |v_y| > 0.9), made orthogonal to v; right = (-v) x up;
/// square pixels, the shorter side spans [-s R, s R] (s = frame_scale); pixel (0, 0) is at the
/// top left. `supersampling` n: each pixel value is the mean over n x n stratified points of the
/// pixel (the centres of an n x n grid); points off the sphere's disc count as 0, as in
/// volpath's image-plane average.
struct SphereView {
    std::array<double, 3> to_light{0, 0, 1};
    std::array<double, 3> to_camera{0, 0, 1};
    std::array<double, 3> up{0, 0, 0};
    int width = 128, height = 128;
    double frame_scale = 1.1;
    int supersampling = 4;
};

/// The resolved frame of a SphereView, lengths in units of R.
struct SphereViewFrame {
    std::array<double, 3> l, v, right, up;
    double pixel = 0;               ///< side of a pixel [R]
    double half_x = 0, half_y = 0;  ///< the frame spans [-half_x, half_x] x [-half_y, half_y] [R]
    int width = 0, height = 0;
    /// Image-plane coordinates (along right, up) [R] of the point (x + fx, y + fy) of the image,
    /// fx, fy in [0, 1] from the pixel's top-left corner ((0.5, 0.5): its centre).
    std::array<double, 2> image_point(int x, int y, double fx = 0.5, double fy = 0.5) const;
};

/// Checks and resolves a view: throws std::invalid_argument naming the field for non-finite or
/// zero direction vectors, an up vector parallel to to_camera, a size outside [1, 16384], a
/// frame_scale that is not finite and > 0, or supersampling outside [1, 64].
SphereViewFrame resolve_view(const SphereView& view);

/// The image of M / pi [1/sr per unit E0] (volpath's "exitance" layer): width x height values,
/// row-major from the top-left pixel, each the pixel average of table.at(beta) / pi.
std::vector<double> sphere_exitance_image(const SphereExitance& table, const SphereView& view);

}  // namespace ssslab::approx
