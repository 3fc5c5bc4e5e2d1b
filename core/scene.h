// Scene files (TOML), shared by the path tracer and the real-time renderers: a pinhole camera,
// lights, materials (a scattering medium behind a dielectric boundary, or an opaque diffuse
// surface) and shapes (procedural or OBJ meshes) in a world unit of `unit_mm` millimetres.
//
// Every value is validated before anything renders: unknown keys ("did you mean"), missing
// files, non-finite or out-of-range numbers, negative coefficients, NaN vertices, and open or
// inconsistently oriented meshes bound to a medium are InputErrors naming file, line and key.
//
//   [scene]      name, description, unit_mm (default 1: one world unit is a millimetre)
//   [camera]     position, target, up ([0, 1, 0]), fov_y_deg, width, height
//   [[lights]]   type = "directional" (direction towards the light, irradiance [RGB],
//                angular_radius_deg = 0), "point" (position, intensity [RGB]), "sphere"
//                (position, radius, radiance [RGB]), "environment" (radiance [RGB]) or "spot"
//                (position, direction it points in, intensity [RGB] on its axis,
//                inner_cone_angle_deg = 0, outer_cone_angle_deg = 45: KHR_lights_punctual);
//                relative linear RGB units (irradiance per unit area, intensity per steradian)
//   [[materials]] name; type = "medium" (a Freude14 preset or sigma_a/sigma_s per mm or per cm,
//                g, eta: the keys of a [material] table; roughness = GGX alpha of the boundary,
//                0 for a smooth one; density_vdb and density_grid for a heterogeneous medium
//                from an OpenVDB float grid scaling the coefficients) or "diffuse" (albedo [RGB])
//   [[shapes]]   type = "sphere" (radius, subdivisions), "box" (size), "torus" (major_radius,
//                minor_radius, segments_major, segments_minor), "plane" (size_x, size_z, facing
//                +y), "bumpy_sphere" (radius, amplitude, frequency, seed, subdivisions) or "mesh"
//                (file, relative to the scene file); material; then scale, rotate_deg (about x, y,
//                z in turn) and translate place it.
#pragma once

#include "core/error.h"
#include "core/hash.h"
#include "core/light.h"
#include "core/material.h"
#include "core/mesh.h"
#include "core/vec3.h"

#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ssslab {

struct SceneCamera {
    Vec3 position{0, 0, 10}, target{0, 0, 0}, up{0, 1, 0};
    double fov_y_deg = 30;  ///< vertical field of view
    int width = 512, height = 512;
};

/// A medium's boundary as every engine resolves it: the relative index of refraction and the GGX
/// alpha of the interface (0 where the index matches: nothing to be rough about).
struct SurfaceBoundary {
    double eta = 1;
    double alpha = 0;
};

struct SceneMaterial {
    enum class Kind { kMedium, kDiffuse };
    std::string name;
    Kind kind = Kind::kMedium;
    /// kMedium: coefficients per cm, as everywhere in ssslab (Scene::per_world_unit converts).
    Medium medium;
    /// kMedium: the preset the coefficients came from ("Skin1"; empty for explicit ones), for
    /// what is tabulated per preset (Freude14 Table A.1's manual kernel parameters).
    std::string preset;
    double roughness = 0;  ///< kMedium: GGX alpha of the boundary (0: smooth)
    /// kMedium, heterogeneous: an OpenVDB file (resolved path; empty: homogeneous) and the float
    /// grid in it whose density scales sigma_a and sigma_s (positions in world units).
    std::string density_file, density_grid = "density";
    std::array<double, 3> albedo{};  ///< kDiffuse
    SourceLocation where;

    /// kMedium: the boundary the engines render (path tracer, CPU lighting, GL twin).
    SurfaceBoundary boundary() const { return {medium.eta, medium.eta == 1.0 ? 0.0 : roughness}; }
};

struct SceneShape {
    std::string name;   ///< "shapes[3]" unless given
    std::string type;   ///< sphere, box, torus, plane, bumpy_sphere, mesh
    int material = 0;   ///< index into Scene::materials
    TriangleMesh mesh;  ///< tessellated and placed, in world units
    std::string file;   ///< type = "mesh": the OBJ file as resolved
    /// type = "sphere" without rotation or non-uniform scale: the exact sphere (renderers may
    /// intersect it analytically instead of its tessellation).
    bool exact_sphere = false;
    /// check_mesh(mesh).closed() as read_scene found it; unset for a shape built in code (a
    /// renderer that needs it then checks the mesh itself).
    std::optional<bool> closed;
    Vec3 center{};
    double radius = 0;
    SourceLocation where;
};

struct Scene {
    std::string name, description;
    std::string path;  ///< the file it came from
    /// The scene as resolved (every value read, defaults included, presets by name), TOML: what
    /// outputs write beside them as the configuration that produced them.
    std::string resolved_toml;
    double unit_mm = 1.0;  ///< one world unit in millimetres
    SceneCamera camera;
    std::vector<SceneLight> lights;
    std::vector<SceneMaterial> materials;
    std::vector<SceneShape> shapes;

    /// A coefficient per cm as per world unit.
    double per_world_unit(double per_cm) const { return per_cm * unit_mm / 10.0; }
    std::size_t triangles() const;
    /// Whether any shape is bound to a medium (the path tracer then traces subsurface light).
    bool has_media() const;
    /// Whether a delta light (directional with radius 0, point) lights a smooth medium boundary
    /// (other than an index-matched one of a homogeneous medium, which shadow rays cross):
    /// a unidirectional path tracer cannot connect it through the boundary (it renders the
    /// subsurface light of that shape black), so the path tracer refuses such scenes.
    bool delta_light_through_smooth_boundary() const;
};

/// Read and validate a scene file; OBJ files are read relative to its folder.
Scene read_scene(const std::string& path);
/// The same from text; `name` is used in messages, `base_dir` resolves mesh files.
Scene parse_scene(std::string_view text, const std::string& name, const std::string& base_dir);

/// Everything in a scene that determines an image, as lines of a content key: the resolved
/// values (a preset as its coefficients), each shape's placed mesh as a hash of its vertices and
/// triangles (so an OBJ file's content is in it), and the content of every OpenVDB file a
/// medium reads. Item names say where in the scene a value is (`materials[1].sigma_a_per_cm`,
/// `shapes[2].mesh`), so that core/hash.h's key_difference names what changed. The one
/// fingerprint of a scene: render checkpoints and the runner's cached renders use it.
void add_to_key(ContentKey& k, const Scene& s);

/// One line per part (camera, lights, materials, shapes with triangle counts and bounds).
std::string describe(const Scene& s);

}  // namespace ssslab
