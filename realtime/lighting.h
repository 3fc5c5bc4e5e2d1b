// Pass 1 of the real-time renderer: the G-buffer and its lighting (issue 13; docs/architecture.md,
// "The real-time renderer"). From a rasterized frame (realtime/raster.h) and the scene: per sample
// the facet normal and material, the irradiance transmitted into a medium through its dielectric
// boundary, the exit weight that turns the medium's exitance into radiance towards the camera,
// the first-surface reflection ("specular"), the radiance of diffuse surfaces and of what is
// seen directly ("surface"), and the thickness and translucency of thin parts
// [Jimenez et al. 2010, "Real-time realistic skin translucency"].
//
// Every light is a set of shadow-mapped point or directional samples (realtime/shadow_map.h):
// a delta directional light one orthographic map, the sun's disc `light_samples` directions in
// its cone, a point light one perspective map (or cube faces), a sphere light `light_samples`
// points on the cap of it the receivers can see, each a point light of the exact cosine-lobed
// intensity of its patch of the surface (so that the sum converges to the sphere's irradiance),
// the constant environment `environment_samples` directions over the sphere. Samples are
// stratified deterministically (Fibonacci spirals), maps are rendered one at a time and their
// contributions summed per G-buffer sample in light order: bit-identical for any thread count.
//
// The boundary is volpath's (core/dielectric.h): Fresnel for a smooth one, the GGX rough
// dielectric [Walter et al. 2007] for roughness alpha; diffuse surfaces are Lambert, two-sided.
#pragma once

#include "core/scene.h"
#include "realtime/raster.h"
#include "realtime/shadow_map.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ssslab::realtime {

struct LightingOptions {
    /// Stratified samples per finite light: points on a sphere light, directions in the sun's
    /// disc (angular_radius_deg > 0).
    int light_samples = 16;
    /// Stratified directions of the constant environment light, each a shadow-mapped
    /// directional light.
    int environment_samples = 64;
    int shadow_map_size = 2048;  ///< texels per side
    /// Texels per side of each environment direction's map: light from many directions, each
    /// a small share, blurs the shadows that a coarse map resolves (64 maps at 2048 would cost
    /// more than everything else in a frame).
    int environment_map_size = 512;
    bool shadows = true;
    /// Fill GBuffer::thickness, the first light's thickness view: a diagnostic layer that no
    /// later pass reads (translucency looks the thickness up per light sample itself), so off
    /// by default; on, it costs a filtered map lookup per medium sample and, for a sun's disc
    /// or a sphere light, a map of its own from the light's centre.
    bool thickness_layer = false;
    /// Shadow tests look the receiver up at p + n * normal_offset_texels * texel (n the facet
    /// normal on the light's side, texel the map's texel size at p) [Holbert 2011, "Saying
    /// goodbye to shadow acne"], and call it lit when its depth is at most the map's plus
    /// depth_bias_texels * texel.
    double normal_offset_texels = 1.0;
    double depth_bias_texels = 1.0;
    /// GGX directional transmittance tables: cosines tabulated (uniform in cos theta, linear
    /// interpolation) and the quadrature's points per axis of the microfacet normals.
    int transmittance_cosines = 65;
    int transmittance_quadrature = 64;
};

/// Per SAMPLE of the frame (frame.sample_width() x frame.sample_height(), row-major, y down),
/// plain arrays. Sphere lights are not rasterized (nor in volpath's BVH): where one lies in
/// front of the geometry, `surface` holds its radiance and the lighting layers are 0 (view_z,
/// shape, material and normal still describe the geometry behind it).
struct GBuffer {
    int width = 0, height = 0;  ///< samples
    std::vector<float> view_z;  ///< RasterFrame::view_z (+inf: nothing)
    std::vector<float> ray_t;   ///< RasterFrame::ray_t (0: nothing)
    /// 3 per sample: the facet normal as volpath's "normal" layer holds it: the triangle's
    /// geometric normal, outward for the mesh's winding (not turned towards the camera); 0 for
    /// nothing.
    std::vector<float> normal;
    std::vector<std::int32_t> shape;     ///< scene shape index, -1 nothing
    std::vector<std::int32_t> material;  ///< scene material index, -1 nothing
    /// 3: irradiance transmitted into the medium through its boundary (medium samples seen from
    /// outside; 0 elsewhere): sum over light samples of T(w_i) E_i cos(theta_i), shadowed.
    std::vector<float> irradiance;
    /// 1: radiance towards the camera per unit exitance leaving the medium, T(w_o) / (pi c)
    /// (BoundaryTransmittance::exit_weight). Medium samples; 0 elsewhere.
    std::vector<float> exit_weight;
    /// 3: radiance reflected off a medium's boundary towards the camera, direct light only
    /// (volpath's "specular" layer at max_depth = 1): GGX reflection of every light sample, or
    /// for a smooth boundary F times the radiance of the sphere lights, environment and suns
    /// in the mirror direction (unoccluded: no ray tracing here).
    std::vector<float> specular;
    /// 3: radiance of diffuse (Lambert) surfaces from direct light, plus emitters and the
    /// environment seen directly (what volpath's radiance holds there at max_depth = 1).
    std::vector<float> surface;
    /// 1 (LightingOptions::thickness_layer; 0 without): for medium samples, the medium
    /// thickness the first light's rays cross before
    /// reaching this point: distance from its shadow map's first hit, when that is the same
    /// shape, to the point [world units]; 0 where none. The first light is the first one of the
    /// scene that is not the environment; sphere lights and suns are taken from their centre.
    std::vector<float> thickness;
    /// 3: exitance at medium samples from light transmitted through thin parts [Jimenez10],
    /// generalised: sum over light samples of E_i max(0, -n.w_i) T_slab(d_i), d_i the shadow-map
    /// thickness along w_i in mm and T_slab the material's slab transmittance table; 0 where
    /// the table is empty.
    std::vector<float> translucency;

    std::size_t samples() const {
        return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    }
    /// Every array sized for w x h samples (sized only: a reused G-buffer of the same size keeps
    /// its storage and values; every backend of pass 1 writes every entry).
    void resize(int w, int h);
};

/// Diffuse transmittance of a slab of the material (normal incidence) against thickness, from
/// an MC engine (the caller computes it); empty: no translucency.
struct SlabTransmittance {
    std::vector<double> thickness_mm;                  ///< increasing
    std::vector<std::array<double, 3>> transmittance;  ///< per thickness, RGB
    /// Interpolated at d mm: log-linear in T between the entries (linear where one is 0),
    /// clamped to the first and last entry outside them; 0 for an empty table.
    std::array<double, 3> at(double d_mm) const;
    /// No table: no translucency for the material.
    bool empty() const { return thickness_mm.empty() || transmittance.empty(); }
};
/// Whether any material has thicknesses tabulated: pass 1 then renders the shadow map of every
/// light sample (translucency looks thickness up there), with or without shadows.
bool any_slab_table(const std::vector<SlabTransmittance>& slabs);

/// Directional transmittance of a medium's boundary for light arriving from outside at cosine
/// mu: 1 - F(mu, eta) for a smooth boundary (alpha = 0); for GGX alpha the transmission lobe of
/// volpath's rough dielectric (core/dielectric.h, importance transport: flux) integrated over
/// the inside hemisphere, tabulated once by deterministic quadrature over the microfacet normals
/// (midpoint rule in the GGX distribution's own coordinates, so that narrow lobes are resolved)
/// and interpolated linearly in mu.
class BoundaryTransmittance {
  public:
    BoundaryTransmittance(double eta, double alpha, int cosines = 65, int quadrature = 64);
    double eta() const { return eta_; }
    double alpha() const { return alpha_; }
    double operator()(double mu) const;
    /// c = (1/pi) integral of T(w) cos over the hemisphere = 2 integral_0^1 T(mu) mu dmu
    /// (exactly, for the interpolated table).
    double hemispherical() const { return c_; }
    /// Radiance leaving per unit exitance at cosine mu_o: T(mu_o) / (pi c), so that
    /// integral of exit_weight cos over the hemisphere is 1.
    double exit_weight(double mu_o) const;
    /// The quadrature itself at one cosine (alpha > 0).
    static double ggx(double mu, double eta, double alpha, int quadrature);

  private:
    double eta_ = 1, alpha_ = 0, c_ = 1;
    std::vector<double> table_;  // GGX: T at mu = k / (n - 1)
};

/// The table of BoundaryTransmittance(eta, alpha, cosines, quadrature), built on first use and
/// kept for the life of the process (thread-safe; the reference stays valid).
const BoundaryTransmittance& tabulated_boundary(double eta, double alpha, int cosines = 65,
                                                int quadrature = 64);

/// One shadow-mapped light sample of pass 1: a direction (orthographic map) or a point
/// (perspective map, or cube faces). What every backend of the pass lights with (the GL twin,
/// realtime/gl/lighting_gl.h, uploads them as they are).
struct LightSample : LightEmitter {
    // The emitter (core/light.h LightEmitter: a direction or a point, its value and angular
    // profile), and what pass 1 does with it:
    bool thickness_view = false;  ///< its map gives GBuffer::thickness
    bool lights = true;           ///< false: a thickness view only
    int light = -1;               ///< index in Scene::lights
};

/// The light samples of a frame and what their shadow maps are fitted to.
struct LightPlan {
    Box receivers;    ///< what the camera sees lit (diffuse surfaces, media seen from outside)
    Box casters;      ///< every shape of the scene
    double near = 0;  ///< point lights' near plane: 1e-6 of the casters' diagonal
    std::vector<LightSample> samples;  ///< in scene order, each light's samples in turn
    std::vector<Light> lights;         ///< the scene's lights resolved (core/light.h), in order
    /// The shadow views of sample s: one orthographic map for a direction (the environment's
    /// at environment_map_size), fit_point's frustum or cube faces for a point.
    std::vector<ShadowView> views(const LightSample& s, const LightingOptions& o) const;
};
/// Every light of the scene as samples (see the file comment), stratified deterministically
/// (Fibonacci), for receivers within `receivers`: sphere lights sample the cap of them that
/// the box can see (none for an empty box).
LightPlan plan_lights(const Scene& scene, const Box& receivers, const LightingOptions& o);
/// The same with the scene's lights already resolved (`resolved`: Light(scene.lights[k]) for
/// every k, in order), moved into LightPlan::lights: what a pass that reads the lights before it
/// plans (shade(), the GL twin) resolves once. std::invalid_argument if the count differs.
LightPlan plan_lights(const Scene& scene, const Box& receivers, const LightingOptions& o,
                      std::vector<Light> resolved);

struct LightingStats {
    int shadow_maps = 0;
    double shadow_ms = 0, shading_ms = 0;
    int light_samples = 0;  ///< point and directional samples of all lights (with or without map)
};

/// The options' ranges (std::invalid_argument "lighting: options out of range").
void check_lighting_options(const LightingOptions& o);

/// What shade() checks of its inputs (every backend of pass 1 calls it): std::invalid_argument
/// for a frame that does not match the camera or options out of range.
void check_lighting_inputs(const RasterCamera& camera, const RasterFrame& frame,
                           const LightingOptions& o);

/// Pass 1. `camera` is the camera the frame was rasterized with
/// (RasterCamera::from_scene(scene.camera, frame.width, frame.height)); with supersampling the
/// G-buffer is at the sample grid. `slabs` is indexed by scene material (may be empty or
/// shorter: no translucency). Throws std::invalid_argument for a frame that does not match the
/// camera or options out of range.
GBuffer shade(const Scene& scene, const RasterCamera& camera, const RasterFrame& frame,
              const LightingOptions& o, const std::vector<SlabTransmittance>& slabs = {},
              LightingStats* stats = nullptr);
/// The same into `out`, whose arrays keep their storage when the size is unchanged (a renderer
/// reuses its G-buffer frame after frame).
void shade(const Scene& scene, const RasterCamera& camera, const RasterFrame& frame,
           const LightingOptions& o, const std::vector<SlabTransmittance>& slabs,
           LightingStats* stats, GBuffer& out);

/// A point on a medium's boundary for boundary_irradiance: position [world units], the outward
/// facet normal (unit) and the scene material (a medium).
struct BoundaryPoint {
    Vec3 p, n;
    int material = -1;
};

/// The irradiance transmitted into the medium at each point as pass 1 computes it for a medium
/// sample of the G-buffer (GBuffer::irradiance): the sum over the light samples of
/// T(cos) E cos where cos = n . w_i > 0, shadowed through the same shadow maps and normal-offset
/// test, behind-sphere occlusion included; lights planned (and shadow maps fitted) for
/// `receivers`, or for the points' bounding box where it is empty. Points
/// the camera does not see are lit as those it does: what a point cloud on the media's surfaces
/// needs (Jensen-Buhler [Bitterli13 §2.6.4], experiments/runner). No translucency (a point cloud
/// has the far sides' own points). Throws std::invalid_argument for a point whose material is not
/// a medium or whose normal or position is not finite, or options out of range.
std::vector<std::array<double, 3>> boundary_irradiance(const Scene& scene,
                                                       const std::vector<BoundaryPoint>& points,
                                                       const LightingOptions& o,
                                                       const Box& receivers = {},
                                                       LightingStats* stats = nullptr);

}  // namespace ssslab::realtime
