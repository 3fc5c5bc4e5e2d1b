// Ground-truth images of scene files (core/scene.h): a unidirectional volumetric path tracer
// with next-event estimation, through Embree. Camera paths; diffuse surfaces (Lambert) and media
// behind a smooth or rough (GGX, volpath/microfacet.h) dielectric boundary; homogeneous media
// inside closed meshes, traced with the hero walk of volpath/walk.h (one path for RGB, spectral
// MIS; absorption by the hero's roulette, or in the weights where every albedo is at least 0.9:
// render_absorption); lights: spherical area lights,
// a constant environment, directional lights (a disc of finite angular radius, or a delta) and
// point lights.
//
// Next-event estimation at every diffuse vertex and at every rough boundary vertex (from
// outside: the reflection lobe; from inside: the transmission lobe, which is what lets delta
// lights reach a medium behind a rough boundary), combined with BSDF sampling by the power
// heuristic. Index-matched boundaries (eta = 1) of homogeneous media are no vertices: shadow
// rays cross them with the medium's transmittance, and inside such a medium NEE is done at
// every scattering vertex (MIS with phase sampling when g is the same in all channels). A smooth
// boundary cannot be connected (a delta BSDF): behind it only light that BSDF sampling finds
// arrives, which is why the built-in scenes use rough boundaries or area lights, and scene files
// whose delta lights shine on smooth media are refused
// (Scene::delta_light_through_smooth_boundary). Behind a rough boundary the light of a sphere
// light or a sun disc also reaches the walk's scattering vertices near the way out through the
// exit guide (RenderOptions::exit_guide, volpath-render-8): NEE of the light through the
// boundary from a point the vertex reaches along a direction that the boundary refracts towards
// the light, combined with the walk's own ways to the same paths by the balance heuristic; since
// volpath-render-9 also from the boundary's own vertices from which a walk goes on inside (the
// entry, an internal reflection: light that crosses a thin medium without a collision).
//
// Film: per pixel the radiance, its subsurface part (light that entered a medium), its
// surface-specular part (first-surface reflection off a medium's boundary), their standard
// errors from the batch statistics, and the first hit's depth and normal. One batch is three
// samples per pixel of the whole image, one per hero channel (the hero choice stratified, so
// that the batches are i.i.d. and their spread is the estimator's error), on stream (seed,
// kRender, batch): the image is bit-identical for any thread count, and a run resumes from its
// checkpoint. Sample budgets are rounded up to a multiple of three.
#pragma once

#include "core/batch_runner.h"
#include "core/enum_names.h"
#include "core/film_image.h"
#include "core/scene.h"
#include "core/stats.h"
#include "volpath/walk.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace ssslab::volpath {

const char* render_engine_version();

/// What a relative-error budget (RenderOptions::budget.rel_error) measures.
enum class RenderErrorMeasure {
    /// The median over the pixel channels that see anything of the radiance's relative standard
    /// error (core/stats.h relative_error): the image has converged to 1 % when half of its
    /// lit pixels have.
    kMedianPixel,
    /// The relative standard error of the image mean of the radiance: far smaller than any
    /// pixel's (it averages over all of them); a measure of the total, not of the image.
    kImageMean,
};
const char* to_string(RenderErrorMeasure m);

/// Where a camera path's first random numbers come from.
enum class RenderSampler {
    kIndependent,  ///< the batch's stream alone (volpath-render-3 and before)
    /// The first 2 x kSobolPairs numbers of a path are Owen-scrambled 2D Sobol points
    /// (core/sobol.h), one independently scrambled pair of dimensions after another, seeded per
    /// batch, pixel and hero from the batch's stream: the samples of one pixel and hero in a
    /// batch form a scrambled (0, m, 2)-net in every pair (every 1D projection stratified), so
    /// the batches stay i.i.d. (their standard errors valid) and their means vary less.
    kSobol,
};
inline constexpr int kSobolPairs = 8;

/// How the hero channel of a camera path's walks is chosen.
enum class RenderHero {
    /// R, G and B in turn at the path's start (stratified in a batch), for all its walks.
    kUniform,
    /// Anew at every entry into a medium, with probability proportional to the path's
    /// throughput times the medium's albedo in each channel (as Cycles chooses its channel);
    /// the first entry stratified by the path's third of the batch.
    kThroughputAlbedo,
};
const char* to_string(RenderHero h);
}  // namespace ssslab::volpath
template <>
struct ssslab::EnumNames<ssslab::volpath::RenderErrorMeasure> {
    using E = ssslab::volpath::RenderErrorMeasure;
    static constexpr std::array<std::pair<E, std::string_view>, 2> table = {
        {{E::kMedianPixel, "median-pixel"}, {E::kImageMean, "image-mean"}}};
};
template <>
struct ssslab::EnumNames<ssslab::volpath::RenderSampler> {
    using E = ssslab::volpath::RenderSampler;
    static constexpr std::array<std::pair<E, std::string_view>, 2> table = {
        {{E::kSobol, "sobol"}, {E::kIndependent, "independent"}}};
};
template <>
struct ssslab::EnumNames<ssslab::volpath::RenderHero> {
    using E = ssslab::volpath::RenderHero;
    static constexpr std::array<std::pair<E, std::string_view>, 2> table = {
        {{E::kThroughputAlbedo, "throughput-albedo"}, {E::kUniform, "uniform"}}};
};
namespace ssslab::volpath {

/// Run control: RunControl (core/batch_runner.h); the budget is samples per pixel (batch_spp per
/// batch), seconds, or a relative error (error_measure). Snapshots keep the image after 4, 8,
/// 16, ... batches (RenderResult::run.snapshots), for error against time; each holds the whole
/// tally (13 doubles per pixel).
struct RenderOptions : RunControl {
    RenderErrorMeasure error_measure = RenderErrorMeasure::kMedianPixel;
    /// Camera path vertices before Russian roulette may end a path (then survival
    /// max(beta) clamped to [0.05, 1]).
    int roulette_depth = 5;
    /// Surface vertices a camera path may have (boundary crossings count, medium events do
    /// not): the path ends where it would meet geometry once more, after the emission its last
    /// ray sees (sphere lights, environment, the sun's disc) is counted. 0: unlimited; 1: direct
    /// lighting only (NEE and BSDF sampling at the first hit, MIS-weighted as always), the
    /// reference of the real-time renderer's lighting pass (tests/test_lighting.cpp).
    int max_depth = 0;
    /// Long-path roulette inside media [Bitterli13 §3.2], as in the pencil engine.
    std::int64_t long_path_events = 100000;
    /// NEE inside index-matched homogeneous media and shadow rays through their boundaries.
    /// Off: such boundaries are crossed by the path alone, as before (tests compare the two).
    bool index_matched_nee = true;
    /// Skip the boundary queries of flights that stay in a ball no surface enters (deep inside
    /// dense media; volpath/mesh_medium.h MeshGeometry). The image is the same to the bit
    /// either way (a test shows it); off only to show that, and to time the difference.
    bool skip_queries_in_balls = true;
    /// Next-event estimation samples every light at every vertex (one shadow ray each), instead
    /// of one light chosen uniformly: the choice was the largest noise of directly lit surfaces
    /// under a sun and an environment (either the sun's whole share or none of it). Off: as
    /// before (volpath-render-3; tests compare the two).
    bool nee_all_lights = true;
    RenderSampler sampler = RenderSampler::kSobol;
    /// Absorption inside media (volpath/walk.h): analog (the hero's roulette with its albedo;
    /// NEE at a vertex carries the survival probability) or weighted (the albedos in the
    /// weights, Russian roulette below kWeightRouletteThreshold) or per channel (each
    /// channel's strategy weighted where its albedo is at least kPerChannelWeightedAlbedo,
    /// analog below). Unset (the default since volpath-render-5): per medium,
    /// `render_absorption`.
    std::optional<Absorption> absorption;
    /// How a camera path's hero channel is chosen (volpath/walk.h SpectralWeights); the default
    /// since volpath-render-6, kUniform before.
    RenderHero hero = RenderHero::kThroughputAlbedo;
    /// NEE at a surface samples the environment in proportion to cos(theta) about the lit
    /// side's normal (core/light.h Light::sample) instead of uniformly over the sphere (half
    /// of whose samples fell below the surface). Off: as before volpath-render-6.
    bool environment_cosine = true;
    /// Rays leave a surface from the surface point itself, skipping its triangle (the way
    /// Cycles leaves a surface): NEE's shadow rays, which go on through index-matched
    /// boundaries the same way, and the path's rays outside media. Off: as before
    /// volpath-render-7, from eps off the surface along its normal (EmbreeScene::epsilon, 4e-5
    /// of the scene's extent) and on from eps beyond each boundary, which misses an occluder
    /// closer than eps and the exit of a medium thinner than eps: the darker arcs along the
    /// silhouettes of ketchup-matched against Cycles.
    bool rays_from_surface = true;
    /// The exit guide (volpath-render-8): at every scattering vertex inside a medium behind a
    /// rough boundary that lies within kExitGuideReach of the medium's smallest mean free paths
    /// of the way out towards a sphere light or a sun disc, one more estimator of the light
    /// that leaves through that boundary straight from the vertex: a direction from a von
    /// Mises-Fisher lobe about the one the boundary there refracts towards the light, the
    /// flight to the boundary without a collision (its transmittance as a weight), and NEE of
    /// the light through the rough boundary; balance heuristic with the walk's own ways to the
    /// same path (its flight, and at the exit NEE or BSDF sampling). The walk alone finds such
    /// light only where its exit direction happens to fall in the boundary's narrow transmission
    /// lobe towards the light (heavy-tailed: the noise of backlit milk and apple). Off: as before.
    bool exit_guide = true;
    /// With exit_guide, the same estimator also at the vertices on such a boundary from which
    /// the walk goes on inside (the entry from outside, an internal reflection): the light that
    /// crosses the medium from there to the way out without a collision, where two narrow
    /// lobes of the rough boundary (the one the walk's direction comes from, the one towards
    /// the light) meet only in their tails (volpath-render-9; off: volpath-render-8's guides at
    /// scattering vertices only).
    bool boundary_guides = true;
    /// With boundary_guides, a guide at a diffuse vertex that the path reached straight from
    /// the way out of a guided medium: lobes of directions from it that the medium's two
    /// boundaries refract towards a sphere light or a sun disc, each into the entry's exit guide
    /// (DiffuseGuide, volpath/render_guides.h). The caustic a thin medium casts on the surface
    /// under it, seen through the medium, otherwise needs the bounce's cosine to fall into the
    /// entry's narrow lobe (volpath-render-10; off: volpath-render-9).
    bool diffuse_guides = true;
    /// With exit_guide, beside each guide light's narrow lobe a wide one (0.3 rad) about the
    /// same axis: where the boundary's normal varies over the narrow lobe's footprint (a bumpy
    /// surface) it aims through one exit point's normal and misses the others that refract
    /// towards the light (volpath-render-11; off: the single lobe of volpath-render-8 to -10).
    bool wide_lobes = true;
    /// Samples per pixel in a batch, a multiple of 3 (each channel the hero equally often).
    /// 0: 3 x 2^m, the largest with at least 32 batches in a sample budget (3 when there is a
    /// time or an error budget); a render resumed from a checkpoint keeps the size it started
    /// with, so it equals an uninterrupted render of that batch size. Larger
    /// batches let the Sobol points of a batch stratify more finely.
    int batch_spp = 0;
    std::string checkpoint_path;  ///< empty: none
    std::function<void(const BatchProgress&)> on_batch;
    /// Called before the render continues from its checkpoint, with what the checkpoint holds.
    std::function<void(const BatchProgress&)> on_resume;
    /// Render at this size instead of the camera's (0: the camera's), e.g. for tests.
    int width = 0, height = 0;
};

/// Every channel's single-scattering albedo at least this: the renderer weights absorption in
/// the medium (unless RenderOptions::absorption says otherwise). Where absorption is rare, the
/// analog roulette's kill at a random event is the walk's largest noise (measured, 128 x 128,
/// efficiency 1/(MSE x time) weighted over analog: 2.1, 2.5, 1.65x on a smooth eta 1.3 sphere
/// of albedo 0.99, 0.98, 0.94 under a white environment); where it is strong, weighted walks
/// go on with small weights and their NEE costs more than it gives (0.85, 0.75, 0.59x on the
/// built-in ketchup, albedo 0.75, 0.067, 0.02).
inline constexpr double kWeightedAbsorptionAlbedo = 0.9;

/// The absorption policy of a medium's walks: `requested` if set, else weighted where every
/// channel's albedo sigma_s / sigma_t is at least kWeightedAbsorptionAlbedo, else analog.
Absorption render_absorption(const double sigma_s[3], const double sigma_t[3],
                             std::optional<Absorption> requested);

/// Per-pixel tally layout: radiance RGB, subsurface RGB, specular RGB, depth, normal xyz.
struct RenderLayout {
    static constexpr int kRadiance = 0, kSubsurface = 3, kSpecular = 6, kDepth = 9, kNormal = 10;
    static constexpr int kPerPixel = 13;
};

struct RenderResult {
    BatchRunResult run;
    int width = 0, height = 0;
    /// Layers "radiance", "subsurface", "specular" (RGB), "<layer>.stderr" (RGB), "depth" (Y,
    /// world units; 0 where nothing was hit) and "normal" (X, Y, Z), with metadata
    /// ssslab.engine, ssslab.scene, ssslab.spp, ssslab.seed, ssslab.seconds.
    LayeredImage image{1, 1};
    double seconds = 0;
    std::uint64_t spp = 0;
    std::uint64_t rays = 0;  ///< ray queries (intersections and shadow rays)
    int batch_spp = 0;       ///< samples per pixel of a batch (of the checkpoint, if resumed)
    bool interrupted = false;
    /// hash_hex of render_fingerprint: what the checkpoint was keyed by (set when checkpointing).
    std::string content_key;
    /// The absorption policy each medium material's walks used (render_absorption), by the
    /// material's name, in the order the scene's shapes first use them.
    std::vector<std::pair<std::string, Absorption>> media_absorption;
};

/// Checks what the renderer supports beyond Scene's own validation: throws InputError (located
/// at the offending light or material) for a delta light with a smooth medium boundary.
void check_renderable(const Scene& scene);

RenderResult render(const Scene& scene, const RenderOptions& options);

/// The render's own error measures of its radiance (per-element means and standard errors in
/// RenderLayout, e.g. RenderResult::run.mean/se): the per-pixel relative errors (their median)
/// and the relative standard error of the image mean (RelativeError::mean).
RelativeError radiance_rel_error(const std::vector<double>& mean, const std::vector<double>& se);
/// The same from a rendered image's "radiance" and "radiance.stderr" layers (e.g. one read
/// back from an EXR).
RelativeError radiance_rel_error(const LayeredImage& image);

/// A render's error measured against an independent reference of the same image (another seed,
/// usually more samples; both with "radiance" and "radiance.stderr"), beside the run's own
/// estimates, which miss what the run has not sampled (heavy tails). Over the pixel-channels
/// that see anything in the reference.
struct MeasuredError {
    RelativeError own;        ///< radiance_rel_error of the run
    RelativeError reference;  ///< radiance_rel_error of the reference
    /// sqrt(sum (L - L_ref)^2 / sum L_ref^2), and with the reference's own noise taken out,
    /// sqrt(max(0, rel_rmse^2 - sum SE_ref^2 / sum L_ref^2)): the measured image relative RMS
    /// error, to compare with own.rms.
    double rel_rmse = 0, rel_rmse_corrected = 0;
    /// The median over pixel-channels of z^2 = (L - L_ref)^2 / (SE^2 + SE_ref^2) divided by the
    /// median of a chi-square variable with one degree of freedom (0.454936): 1 when the
    /// standard errors say how far pixels are off, above 1 when they say too little.
    double z2_median_ratio = 0;
    /// The measured median pixel relative error: own.median x sqrt(z2_median_ratio).
    double median_pixel = 0;
    std::size_t counted = 0;  ///< pixel-channels compared
};
/// std::invalid_argument if the sizes differ or the reference is black.
MeasuredError measured_error(const LayeredImage& run, const LayeredImage& reference);

/// What a render's checkpoint is keyed by: the renderer's version, the settings that change the
/// image (seed, size, roulette, long paths, NEE, max_depth when not 0), and the scene's content
/// (core/scene.h add_to_key: resolved values, meshes, grid files), as a ContentKey's text. Not the
/// budget: a resumed run may be given more samples.
std::string render_fingerprint(const Scene& scene, const RenderOptions& options);

/// The samples per pixel of a batch for these options (RenderOptions::batch_spp's rule).
int render_batch_spp(const RenderOptions& options);

/// One point of error against time: the radiance after `spp` samples per pixel (a snapshot or
/// the final image) against a reference image.
struct ConvergencePoint {
    std::uint64_t spp = 0;
    double seconds = 0;
    double rel_rmse = 0;     ///< sqrt(sum (L - L_ref)^2 / sum L_ref^2) over pixels and channels
    double mean_rel_se = 0;  ///< the run's own estimate: sqrt(sum SE^2 / sum L_ref^2) (final only)
};
/// Error of every snapshot and of the final image against `reference` (its "radiance" layer,
/// of the same size; std::invalid_argument otherwise).
std::vector<ConvergencePoint> convergence(const RenderResult& r, const LayeredImage& reference);

}  // namespace ssslab::volpath
