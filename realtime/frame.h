// A real-time frame of a scene file: the passes of [Freude14 Algorithm 4.1] in sequence, the CPU
// reference of the GL twin.
//
//   raster     realtime/raster.h: the scene through volpath's camera (s x s samples per pixel)
//   lighting   realtime/lighting.h, pass 1: G-buffer per sample (irradiance transmitted into the
//              medium, specular, diffuse surfaces, thickness and translucency) with shadow maps
//   sss        passes 2-3: realtime/sss_pass.h (a separable model's taps) or, as the screen-space
//              ground truth, realtime/sss_reference.h (the exact 2D kernel); skipped when no
//              medium is in view
//   composite  pass 4: subsurface = exit_weight (albedo sss + translucency); radiance =
//              surface + specular + subsurface; samples box-filtered to pixels
//
// Units of the subsurface term. A material's kernel (approx::Kernel2D, unit L1 on the thesis
// grid) stands for MCML's R_d(r) of a pencil beam at normal incidence, which carries the entry
// factor 1 - R_sp; the G-buffer holds the irradiance that actually entered (T(w_i) E). So the
// exitance per unit entered irradiance is raw_l1 / (1 - R_sp) times the kernel's convolution
// (`FrameMaterial::albedo`), and the radiance toward the camera is exit_weight = T(w_o) / (pi c)
// times the exitance (realtime/lighting.h): Lambertian inside the boundary, Fresnel-weighted
// outside [as pbrt's separable BSSRDF, Sw]. Light that the grid does not hold (beyond 32 max
// MFP) is lost in every model and in the reference alike.
//
// Output: a LayeredImage with the layer names volpath writes -- radiance, subsurface, specular
// (RGB), depth (Y: mean ray distance, 0 where nothing, RasterFrame::depth), normal (XYZ: mean of
// the samples' facet normals) -- plus irradiance (RGB, before the SSS pass), surface (RGB),
// translucency (RGB exitance), material (Y: the scene material index of most of the pixel's
// samples, -1 for none) and, for the reference's sampled pixels, subsurface.stderr (RGB).
//
// Scratch: the SSS pass's inputs and output, the shadow maps and their band frames are kept per
// calling thread between frames (no result depends on them). Frames are therefore rendered one
// at a time per thread: never start a frame from inside another frame's parallel work.
#pragma once

#include "approx/model_spec.h"
#include "core/enum_names.h"
#include "core/film_image.h"
#include "core/profile.h"
#include "core/scene.h"
#include "realtime/lighting.h"
#include "realtime/raster.h"
#include "realtime/sss_pass.h"
#include "realtime/sss_reference.h"

#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace ssslab::realtime {

/// What the SSS passes need of one medium material.
struct FrameMaterial {
    std::string name;
    SssMaterialKernel kernel;             ///< the model's taps (SssMethod::kSeparable)
    std::optional<SssExactKernel> exact;  ///< the exact 2D kernel (SssMethod::kReference)
    /// Exitance per unit entered irradiance that the unit-L1 kernel stands for, per channel:
    /// the grid's share of R_d over 1 - R_sp (see the file comment).
    std::array<double, 3> albedo{};
};

/// The kernels of a material from its ground-truth profile: the thesis grid (KernelGrid::
/// from_profile), one Kernel2D per channel, the model's separable kernel per channel
/// (approx::build_model) as `taps` importance-sampled taps per term, and with `exact` the exact
/// kernel for the reference. Models that fit in image space ("manual:fit=...") need the
/// kernel studies' test images and are refused (std::invalid_argument).
FrameMaterial make_frame_material(const RadialProfile& profile, const approx::ModelSpec& model,
                                  int taps, bool exact);

enum class SssMethod {
    kSeparable,  ///< realtime::sss_pass with the model's taps
    kReference,  ///< realtime::sss_reference: the exact 2D kernel (screen-space ground truth)
    kNone,       ///< no SSS pass: subsurface = exit_weight (albedo E + translucency)
};
}  // namespace ssslab::realtime
template <>
struct ssslab::EnumNames<ssslab::realtime::SssMethod> {
    using E = ssslab::realtime::SssMethod;
    static constexpr std::array<std::pair<E, std::string_view>, 3> table = {
        {{E::kSeparable, "separable"}, {E::kReference, "reference"}, {E::kNone, "none"}}};
};
namespace ssslab::realtime {
const char* to_string(SssMethod m);
/// The kernel a frame's SSS pass applied, as outputs name it: the model's spec for the separable
/// pass, "reference:2d" (the material's exact 2D kernel, the name Table 6.4's rows give it) for
/// the reference, "none" without a pass.
std::string sss_kernel_name(SssMethod m, const std::string& model_spec);

/// The raster options of a frame: RasterOptions' defaults without barycentrics and fragment
/// counts, which no pass of a frame reads.
inline RasterOptions frame_raster_options() {
    RasterOptions r;
    r.barycentrics = false;
    r.count_fragments = false;
    return r;
}

struct FrameOptions {
    int width = 0, height = 0;  ///< 0: the scene camera's size
    /// Supersample, tiles, near plane, culling. Pass 1 reads depth, shape and triangle only,
    /// so a frame's raster fills no barycentrics and counts no fragments.
    RasterOptions raster = frame_raster_options();
    LightingOptions lighting;
    SssMethod method = SssMethod::kSeparable;
    /// Edge mode, follow-surface strength, rejection depth, jitter, seed; tan_half, aspect and
    /// unit_mm are set from the scene and camera.
    SssParams sss;
    SssReferenceOptions reference;
    /// false: pass 4 writes the radiance layer only (what a game presents: `ssslab bench
    /// --realtime` times its frames so); true: every layer of the file comment.
    bool all_layers = true;
    /// The raster's backend: realtime::rasterize when empty; the GL twin
    /// (realtime/gl/raster_gl.h, through realtime/gl/frame_gl.h) plugs in here.
    std::function<void(const Scene&, const RasterOptions&, int width, int height, RasterFrame&)>
        rasterizer;
    /// Pass 1's backend: realtime::shade when empty; the GL twin (realtime/gl/lighting_gl.h)
    /// plugs in here, with the same inputs and the same G-buffer.
    std::function<void(const Scene&, const RasterCamera&, const RasterFrame&,
                       const LightingOptions&, const std::vector<SlabTransmittance>&,
                       LightingStats*, GBuffer&)>
        lighting_pass;
    /// The separable pass's backend (SssMethod::kSeparable): realtime::sss_pass when empty; the
    /// GL twin (realtime/gl/sss_pass_gl.h) plugs in here, with the same plain-data inputs. The
    /// frame's "sss" time is then this call's wall time (uploads and read-back included).
    std::function<void(const SssGBuffer&, const std::vector<SssMaterialKernel>&, const SssParams&,
                       std::vector<float>&)>
        separable_pass;
};

/// Checks what the real-time renderer supports beyond Scene's own validation: homogeneous media
/// only (one kernel per material). Throws InputError located at the offending material.
void check_drawable(const Scene& scene);

/// Edge parameters in a scene's units: follow-surface strength 3.6 per mm of depth difference
/// (the separable-sss demo's C SSS_w = 300 x 0.012, its scene unit read as a mm) and rejection
/// beyond 1 mm of depth difference, as world units of the scene.
inline double default_follow_strength(const Scene& s) {
    return 3.6 * s.unit_mm;
}
inline double default_reject_depth(const Scene& s) {
    return 1.0 / s.unit_mm;
}

/// A rasterized frame, before the materials are known: callers look at media_in_view to build
/// only the kernels the frame needs.
struct RasterizedFrame {
    RasterCamera camera;  ///< at the sample grid's size
    RasterFrame raster;
    double ms = 0;
    std::vector<int> media_in_view;  ///< scene material indices of media covering a sample
    std::vector<int> lit_in_view;    ///< every scene material covering a sample
};
RasterizedFrame rasterize_frame(const Scene& scene, const FrameOptions& o);
/// The same into `out`, reusing its storage (a renderer drawing frame after frame).
void rasterize_frame(const Scene& scene, const FrameOptions& o, RasterizedFrame& out);

struct PassTime {
    std::string pass;  ///< "raster", "shadow maps", "lighting", "sss", "composite"
    double ms = 0;
};

/// Pass 1 of a frame: what every SSS variant of it shares (a study scores many models on one
/// G-buffer: it lights the frame once).
struct LitFrame {
    GBuffer gbuffer;
    LightingStats stats;
    double ms = 0;  ///< the whole pass (shadow maps and shading)
};
/// `slabs` (by scene material) feed translucency and may be empty.
LitFrame light_frame(const Scene& scene, const RasterizedFrame& frame, const FrameOptions& o,
                     const std::vector<SlabTransmittance>& slabs = {});
/// The same into `out`, reusing its G-buffer's storage.
void light_frame(const Scene& scene, const RasterizedFrame& frame, const FrameOptions& o,
                 LitFrame& out, const std::vector<SlabTransmittance>& slabs = {});

struct FrameResult {
    LayeredImage image{1, 1};
    std::vector<PassTime> times;  ///< every pass, in order, including the raster's
    LightingStats lighting;
    std::int64_t sss_exact_pixels = 0, sss_sampled_pixels = 0;  ///< kReference
    double total_ms() const;
};

/// Passes 2-4 on a lit frame (its times, and the raster's, are the result's first entries).
/// `materials` must hold every medium in frame.media_in_view (std::invalid_argument naming the
/// missing one otherwise).
FrameResult render_frame(const Scene& scene, const RasterizedFrame& frame, const LitFrame& lit,
                         const std::map<int, FrameMaterial>& materials, const FrameOptions& o);
/// The passes after the raster: light_frame, then the above.
FrameResult render_frame(const Scene& scene, const RasterizedFrame& frame,
                         const std::map<int, FrameMaterial>& materials, const FrameOptions& o,
                         const std::vector<SlabTransmittance>& slabs = {});

}  // namespace ssslab::realtime
