// Ground truth for a homogeneous sphere under a directional light, by light tracing
// [Bitterli13 §3.1.3 "Lit Sphere Modules", §3.2 Alg. 1, §3.5]: the reference that analytic
// BSSRDFs integrated over the sphere (Bitterli13 §3.5) are compared with.
//
// Scene: a sphere of radius R centred at the origin, filled with a homogeneous medium behind a
// smooth dielectric boundary (medium index eta, ambient index eta_above). A directional light of
// irradiance E0 = 1 (per unit area perpendicular to it) arrives travelling along -l. A camera
// direction v (towards the camera) defines an orthographic image.
//
// Why light tracing: a smooth dielectric boundary and a delta light cannot be connected by a
// camera path (it would need the exact refracted direction), so photons are traced from the light.
// Each photon enters at a point uniform on the disc of radius R perpendicular to l, i.e. it
// carries the flux pi R^2 E0 / N; the Fresnel reflectance F at the entry point is split off
// deterministically (first-surface specular, weight F), and the rest (weight 1 - F) performs the
// random walk of volpath/pencil.cpp (free paths, Henyey-Greenstein, Fresnel roulette with total
// internal reflection, the sampled free path continues after an internal reflection, albedo
// roulette or hero-wavelength MIS, long-path roulette) inside the sphere until it leaves.
//
// Every tally is a mean per photon, i.e. a fraction of the incident flux pi R^2 E0, with its
// batch-means standard error (core/batch_runner.h); SphereRun converts them to physical units.
#pragma once

#include "core/batch_runner.h"
#include "core/film_image.h"
#include "core/material.h"
#include "volpath/pencil.h"
#include "volpath/sampling.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace ssslab::volpath {

/// Version of the numbers the sphere engine produces for a given seed (part of every checkpoint
/// fingerprint and cache key): bump it when a change alters them.
const char* sphere_engine_version();

/// The lit sphere and its camera.
///
/// | field          | unit        | default       | meaning                                      |
/// |----------------|-------------|---------------|----------------------------------------------|
/// | medium         | 1/cm, -     |               | sigma_a, sigma_s, g per channel; eta (sphere)|
/// |                |             |               | and eta_above (ambient); eta_below and       |
/// |                |             |               | thickness_cm are ignored                     |
/// | radius_cm      | cm          | 1             | sphere radius R                              |
/// | to_light       | -           | (0, 0, 1)     | l, towards the light (normalised here)       |
/// | to_camera      | -           | (0, 0, 1)     | v, towards the camera (normalised here)      |
/// | up             | -           | (0, 0, 0)     | camera up; zero: +y, or -sign(v_y) z when    |
/// |                |             |               | |v_y| > 0.9 (keeps +x to the right)          |
/// | width, height  | pixels      | 128 x 128     | image size; square pixels, the shorter side  |
/// |                |             |               | spans [-s R, s R]                            |
/// | frame_scale    | -           | 1.1           | s                                            |
/// | acceptance_deg | degrees     | 10            | half-angle theta_c of the radiance sensor's  |
/// |                |             |               | cone around v, in (0, 90]                    |
/// | beta_bins      | -           | 180           | equal-width bins of beta in [0, pi]          |
struct SphereScene {
    Medium medium;
    double radius_cm = 1.0;
    Vec3 to_light{0, 0, 1};
    Vec3 to_camera{0, 0, 1};
    Vec3 up{0, 0, 0};
    int width = 128, height = 128;
    double frame_scale = 1.1;
    double acceptance_deg = 10.0;
    int beta_bins = 180;
};

/// How a run is carried out; none of these change the expected values.
/// Run control: ChannelRunControl (volpath/pencil.h); the budget counts photons, per channel in
/// kPerChannel mode, for the single run in kHero mode. With no limit, 1e6 photons.
struct SphereOptions : ChannelRunControl {
    /// Photons per batch; 0 chooses: at least 1000 and budget / 1000, and with the image on also
    /// min(2 width height, budget / 32) (2 width height without a fixed photon budget). The
    /// whole tally (image included) is zeroed and folded into the statistics once per batch, an
    /// O(size) cost, so batches must hold several photons per pixel for that cost to vanish
    /// next to the transport; 32 batches at least keep the standard errors meaningful.
    /// Memory: the tally has (beta_bins + 5 + 4 width height) doubles per channel (1 channel
    /// per run in kPerChannel mode, 3 in kHero mode); run_batches holds 2 threads + 2 of them
    /// (batches in flight, sums and squares). A 256 x 256 image in hero mode: 786k doubles,
    /// 6.3 MB per tally, ~215 MB with 16 threads (snapshots add one per power of 2 batches).
    std::int64_t batch_paths = 0;
    ChromaticMode mode = ChromaticMode::kPerChannel;
    /// Long-path roulette [Bitterli13 §3.2], as PencilOptions (0: its rule, 20 / (1 - albedo)
    /// clamped to [1e4, 1e6]).
    std::int64_t long_path_events = 0;
    double long_path_survival = 0.1;
    /// Tally the image layers (off: only the beta profile and the totals).
    bool image = true;
};

/// The image layers, in tally order.
enum class SphereLayer : int {
    /// Image-plane average of the radiant exitance M of the subsurface light over the pixel,
    /// divided by pi: the radiance a Lambertian emitter of that exitance would show [1/sr per
    /// unit E0]. Estimator sum_i w_i (n_i . v) / A_pix: dA_image = (n . v) dA_surface.
    kExitance = 0,
    /// Radiance of the light that entered the medium (the ballistic part included), seen through
    /// a sensor that accepts exit directions within theta_c of v: sum_i w_i / (A_pix Omega_c),
    /// Omega_c = 2 pi (1 - cos theta_c), at the pixel of the exit point's projection along v.
    /// Converges to the radiance as theta_c -> 0 [1/sr per E0].
    kSubsurface = 1,
    /// The same for the first-surface reflection (a highlight where the half vector of l and v
    /// is the normal; total intensity F E0 R^2 / 4 per steradian, the mirror sphere's).
    kSpecular = 2,
    /// kSubsurface + kSpecular, tallied as such (so its standard error includes their covariance).
    kRadiance = 3,
};
inline constexpr int kSphereLayers = 4;
const char* to_string(SphereLayer layer);

/// Tally layout of one channel: beta bins, the totals, then (with the image) 4 layers of
/// width x height pixels, row-major from the top-left pixel. Only exit points visible from the
/// camera (n . v > 0) enter the cone totals and the image.
struct SphereLayout {
    int beta_bins = 0;
    int width = 0, height = 0;
    bool image = false;
    std::size_t beta() const { return 0; }
    /// Weight leaving after having entered the medium (ballistic part included).
    std::size_t diffuse() const { return static_cast<size_t>(beta_bins); }
    std::size_t specular() const { return diffuse() + 1; }  ///< first-surface reflection
    /// As PencilLayout::lost(): the weight of the paths when they reach the long-path roulette
    /// (the mass at risk; in practice survivors seldom return, so the estimate misses about
    /// this much), plus the weight of the rare flight ended after 10^6 boundary hits (a ray
    /// trapped at exactly grazing incidence by total internal reflection).
    std::size_t lost() const { return diffuse() + 2; }
    /// Weight leaving within the acceptance cone, at visible points (subsurface, specular).
    std::size_t cone_subsurface() const { return diffuse() + 3; }
    std::size_t cone_specular() const { return diffuse() + 4; }
    /// The single-scattering part (paths with exactly one scattering event) of diffuse() and
    /// of the beta bins, for the models that leave it out.
    std::size_t diffuse_single() const { return diffuse() + 5; }
    std::size_t beta_single() const { return diffuse() + 6; }
    std::size_t pixels() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
    std::size_t layer(SphereLayer k) const {
        return beta_single() + static_cast<size_t>(beta_bins) + static_cast<size_t>(k) * pixels();
    }
    std::size_t per_channel() const {
        return beta_single() + static_cast<size_t>(beta_bins) +
               (image ? kSphereLayers * pixels() : 0);
    }
};

/// The image geometry: orthonormal camera frame and pixel size.
struct SphereCamera {
    Vec3 v, right, up;  ///< towards the camera; image x (to the right) and y (up)
    double half_x = 0;  ///< the frame spans [-half_x, half_x] x [-half_y, half_y] [cm]
    double half_y = 0;
    double pixel_cm = 0;     ///< side of a (square) pixel in the image plane [cm]
    double solid_angle = 0;  ///< Omega_c of the acceptance cone [sr]
};
/// The camera of a scene (checks it first).
SphereCamera sphere_camera(const SphereScene& scene);

struct SphereRun {
    SphereScene scene;  ///< with to_light, to_camera normalised and up resolved
    SphereCamera camera;
    ChromaticMode mode = ChromaticMode::kPerChannel;
    SphereLayout layout;
    /// kPerChannel: three runs (R, G, B) of one channel each; kHero: one run of three channels.
    std::vector<BatchRunResult> runs;
    bool interrupted = false;

    // Filled unless interrupted.
    /// Radiant exitance of the subsurface light per beta bin (bin j covers
    /// [j, j + 1] pi / beta_bins), divided by E0 [-]: the weight leaving through the zone over
    /// the zone's area 2 pi R^2 (cos b0 - cos b1). The specular part is not included (it is
    /// E0 F(cos beta) cos beta on the lit side).
    std::array<std::vector<double>, 3> exitance, exitance_se;
    /// Its single-scattering part (paths with exactly one scattering event), per beta bin.
    std::array<std::vector<double>, 3> exitance_single, exitance_single_se;
    /// Fractions of the incident flux pi R^2 E0: leaving after entering the medium (the
    /// ballistic part included), reflected by the first surface, at risk in the long-path
    /// roulette (SphereLayout::lost()).
    std::array<double, 3> diffuse{}, diffuse_se{};
    std::array<double, 3> diffuse_single{}, diffuse_single_se{};  ///< its single-scattering part
    std::array<double, 3> specular{}, specular_se{};
    std::array<double, 3> lost{}, lost_se{};
    /// What `specular` estimates, by quadrature: sphere_specular_reflectance(eta / eta_above).
    double specular_expected = 0;
    /// Radiant intensity towards the camera, averaged over the acceptance cone, of the subsurface
    /// light and of the first-surface reflection, per unit E0 [cm^2/sr]: the cone weight times
    /// pi R^2 / Omega_c. The integral of the corresponding image layer over the image plane
    /// when the frame holds the whole sphere.
    std::array<double, 3> intensity_subsurface{}, intensity_subsurface_se{};
    std::array<double, 3> intensity_specular{}, intensity_specular_se{};
    /// With SphereOptions::image: RGB layers "exitance", "subsurface", "specular", "radiance"
    /// (see SphereLayer; per unit E0 [1/sr]) and their standard errors "<layer>.stderr";
    /// metadata ssslab.engine, ssslab.seed, ssslab.photons, ssslab.mode.
    std::optional<LayeredImage> image;
    double seconds = 0;
    std::uint64_t paths = 0, events = 0;

    /// Mean and standard error (per photon) of tally element i of channel c.
    double mean(int c, std::size_t i) const;
    double se(int c, std::size_t i) const;
    /// Lower edge of beta bin j (j = beta_bins gives pi) [rad].
    double beta_edge(int j) const;
};

/// Checks the scene: throws std::invalid_argument naming the field for a radius <= 0, negative
/// or non-finite coefficients, g outside (-1, 1), non-positive indices, degenerate or parallel
/// direction vectors, an image size outside [1, 16384] or an acceptance angle outside (0, 90];
/// InfeasibleError for an image whose tally would not fit (more than 2^27 doubles per batch).
/// sigma_t = 0 is fine: photons cross the sphere.
void check_sphere(const SphereScene& scene, bool image = true,
                  ChromaticMode mode = ChromaticMode::kPerChannel);

/// Fraction of a collimated beam that the first surface of a smooth sphere reflects, for the
/// relative index eta = n_sphere / n_ambient: the disc average 2 int_0^1 F(mu) mu dmu of the
/// Fresnel reflectance (adaptive Gauss-Legendre, split at the critical angle; ~1e-15).
double sphere_specular_reflectance(double eta);

/// Simulate. Deterministic for any thread count: batch b of run s uses the stream
/// (seed, kVolpath + 16 + s, b), s = channel or 3 for kHero (never shared with the pencil runs).
SphereRun simulate_sphere(const SphereScene& scene, const SphereOptions& options);

}  // namespace ssslab::volpath
