#include "core/scene.h"

#include "core/config.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

namespace ssslab {

namespace fs = std::filesystem;

namespace {

std::string required_choice(ConfigTable& t, std::string_view key,
                            std::initializer_list<std::string_view> choices) {
    if (!t.has(key)) {
        std::string list;
        for (auto c : choices) list += (list.empty() ? "" : ", ") + std::string(c);
        t.fail(key, "required: one of " + list);
    }
    return t.choice(key, "", choices);
}

void read_camera(ConfigTable& t, SceneCamera& c) {
    c.position = t.vec3("position");
    c.target = t.vec3("target");
    c.up = t.optional_vec3("up").value_or(Vec3{0, 1, 0});
    c.fov_y_deg = t.number("fov_y_deg", Range::open(0, 180));
    c.width = static_cast<int>(t.integer("width", 512, Range::closed(1, 16384)));
    c.height = static_cast<int>(t.integer("height", 512, Range::closed(1, 16384)));
    const Vec3 view = c.target - c.position;
    if (!(length(view) > 0)) t.fail("target", "the camera's target equals its position");
    if (!(length(c.up) > 0)) t.fail("up", "the up vector is zero");
    if (length(cross(normalize(view), normalize(c.up))) < 1e-6)
        t.fail("up", "the up vector is parallel to the viewing direction");
}

SceneMaterial read_material(ConfigTable& t, const std::string& base_dir) {
    SceneMaterial m;
    m.where = t.location("name");
    m.name = t.string("name");
    if (m.name.empty() || m.name.find_first_of(" \t\"'/\\") != std::string::npos)
        t.fail("name", "expected a material name without spaces, quotes or slashes");
    const std::string type = t.choice("type", "medium", {"medium", "diffuse"});
    if (type == "medium") {
        m.kind = SceneMaterial::Kind::kMedium;
        m.medium = medium_coefficients_from_config(t);
        m.preset = m.medium.name;  // the preset's name, or empty
        m.medium.name = m.name;
        for (int c = 0; c < 3; ++c)
            if (m.medium.g[c] <= -1 || m.medium.g[c] >= 1)
                t.fail_item("g", static_cast<std::size_t>(c),
                            "g must lie in (-1, 1) for the path tracer");
        m.roughness = t.number("roughness", 0.0, Range::closed(0, 1));
        if (auto f = t.optional_string("density_vdb")) {
            fs::path p = *f;
            if (p.is_relative()) p = fs::path(base_dir) / p;
            m.density_file = p.lexically_normal().string();
            std::error_code ec;
            if (!fs::is_regular_file(m.density_file, ec))
                t.fail("density_vdb", "OpenVDB file not found: " + m.density_file);
            m.density_grid = t.string("density_grid", "density");
        }
        if (m.roughness > 0 && m.roughness < 1e-3)
            t.fail("roughness",
                   "a GGX alpha below 1e-3 is numerically a smooth boundary: use 0 (smooth) or "
                   "at least 1e-3");
        // The medium as the engines simulate it, whatever it was given as (a preset's
        // coefficients): into the resolved scene that outputs write beside them.
        ConfigTable sim = t.table_or_empty("simulated");
        auto rgb = [](const std::array<double, 3>& v) {
            return std::vector<double>(v.begin(), v.end());
        };
        sim.record("sigma_a_per_cm", rgb(m.medium.sigma_a_per_cm));
        sim.record("sigma_s_per_cm", rgb(m.medium.sigma_s_per_cm));
        sim.record("g", rgb(m.medium.g));
        sim.record("eta", m.boundary().eta);
        sim.record("ggx_alpha", m.boundary().alpha);
    } else {
        m.kind = SceneMaterial::Kind::kDiffuse;
        m.albedo = t.rgb("albedo", Range::right_open(0, 1));
    }
    return m;
}

Transform read_transform(ConfigTable& t) {
    Transform x;
    if (t.has("scale")) {
        if (auto s = t.optional_rgb("scale", Range::any())) {  // one number or three
            x.scale = {(*s)[0], (*s)[1], (*s)[2]};
            for (std::size_t i = 0; i < 3; ++i)
                if ((*s)[i] == 0) t.fail_item("scale", i, "scale factors must not be 0");
        }
    }
    x.rotate_deg = t.optional_vec3("rotate_deg").value_or(Vec3{});
    x.translate = t.optional_vec3("translate").value_or(Vec3{});
    return x;
}

SceneShape read_shape(ConfigTable& t, const std::string& base_dir,
                      const std::map<std::string, int>& materials,
                      const std::vector<SceneMaterial>& mats, std::size_t index) {
    SceneShape s;
    s.where = t.location("type");
    s.name = t.string("name", "shapes[" + std::to_string(index) + "]");
    s.type =
        required_choice(t, "type", {"sphere", "box", "torus", "plane", "bumpy_sphere", "mesh"});
    TriangleMesh local;
    if (s.type == "sphere") {
        s.radius = t.number("radius", Range::positive());
        local = make_sphere(s.radius,
                            static_cast<int>(t.integer("subdivisions", 5, Range::closed(0, 8))));
    } else if (s.type == "box") {
        local = make_box(t.vec3("size", Range::positive()));
    } else if (s.type == "torus") {
        const double major = t.number("major_radius", Range::positive());
        const double minor = t.number("minor_radius", Range::positive());
        if (!(minor < major))
            t.fail("minor_radius", "the tube radius must be below the ring radius");
        const auto nu = t.integer("segments_major", 128, Range::closed(3, 4096));
        const auto nv = t.integer("segments_minor", 64, Range::closed(3, 4096));
        local = make_torus(major, minor, static_cast<int>(nu), static_cast<int>(nv));
    } else if (s.type == "plane") {
        local =
            make_quad(t.number("size_x", Range::positive()), t.number("size_z", Range::positive()));
    } else if (s.type == "bumpy_sphere") {
        s.radius = t.number("radius", Range::positive());
        const double amplitude = t.number("amplitude", Range::open(-1, 1));
        const double frequency = t.number("frequency", Range::positive());
        const auto seed = static_cast<std::uint64_t>(t.integer("seed", 1, Range::nonnegative()));
        local =
            make_bumpy_sphere(s.radius, amplitude, frequency, seed,
                              static_cast<int>(t.integer("subdivisions", 6, Range::closed(0, 8))));
    } else {
        const std::string file = t.string("file");
        fs::path p = file;
        if (p.is_relative()) p = fs::path(base_dir) / p;
        s.file = p.lexically_normal().string();
        std::error_code ec;
        if (!fs::is_regular_file(s.file, ec)) t.fail("file", "mesh file not found: " + s.file);
        local = load_obj(s.file);
    }
    const Transform x = read_transform(t);
    s.mesh = transformed(local, x);
    if (s.type == "sphere" && x.rotate_deg == Vec3{} && x.scale.x == x.scale.y &&
        x.scale.y == x.scale.z && x.scale.x > 0) {
        s.exact_sphere = true;
        s.center = x.translate;
        s.radius *= x.scale.x;
    }

    const std::string mat = t.string("material");
    auto it = materials.find(mat);
    if (it == materials.end()) {
        std::string list;
        std::vector<std::string> names;
        for (const auto& [k, v] : materials) {
            list += (list.empty() ? "" : ", ") + k;
            names.push_back(k);
        }
        std::string msg = "unknown material \"" + mat + "\"";
        const std::string best = nearest_name(mat, names, suggestion_distance(mat));
        if (!best.empty()) msg += " (did you mean \"" + best + "\"?)";
        t.fail("material", msg + "; the scene's materials: " + list);
    }
    s.material = it->second;
    const MeshCheck check = check_mesh(s.mesh);
    s.closed = check.closed();
    if (check.nonfinite_vertices > 0)
        t.fail(s.type == "mesh" ? "file" : "type",
               "vertex " + std::to_string(check.first_nonfinite_vertex) +
                   " is not finite after placement");
    if (mats[static_cast<size_t>(s.material)].kind == SceneMaterial::Kind::kMedium &&
        (!check.closed() || check.degenerate_triangles > 0))
        t.fail("material",
               "a shape bound to a medium must be a closed, consistently oriented mesh; " + s.name +
                   (s.file.empty() ? "" : " (" + s.file + ")") + " has " + check.describe());
    if (mats[static_cast<size_t>(s.material)].kind == SceneMaterial::Kind::kMedium &&
        !(s.mesh.volume() > 0))
        t.fail("material",
               "the mesh bound to a medium is oriented inwards (negative volume): "
               "flip its faces");
    return s;
}

Scene parse(std::shared_ptr<ConfigDocument> doc, const std::string& path,
            const std::string& base_dir) {
    Scene s;
    s.path = path;
    ConfigTable root = doc->root();
    ConfigTable sc = root.table_or_empty("scene");
    s.name = sc.string("name", fs::path(path).stem().string());
    s.description = sc.string("description", "");
    s.unit_mm = sc.number("unit_mm", 1.0, Range::positive());
    ConfigTable cam = root.require_table("camera");
    read_camera(cam, s.camera);
    for (ConfigTable& t : root.table_array("lights")) s.lights.push_back(read_light(t));
    if (s.lights.empty()) root.fail("lights", "a scene needs at least one [[lights]] table");
    std::map<std::string, int> names;
    for (ConfigTable& t : root.table_array("materials")) {
        s.materials.push_back(read_material(t, base_dir));
        if (!names.emplace(s.materials.back().name, static_cast<int>(s.materials.size() - 1))
                 .second)
            t.fail("name", "material \"" + s.materials.back().name + "\" is defined twice");
    }
    if (s.materials.empty())
        root.fail("materials", "a scene needs at least one [[materials]] table");
    std::size_t i = 0;
    for (ConfigTable& t : root.table_array("shapes"))
        s.shapes.push_back(read_shape(t, base_dir, names, s.materials, i++));
    if (s.shapes.empty()) root.fail("shapes", "a scene needs at least one [[shapes]] table");
    // Media must not overlap other shapes (a path inside a medium that meets another surface
    // has no defined continuation), and the camera must not sit inside a medium.
    for (std::size_t a = 0; a < s.shapes.size(); ++a) {
        const SceneShape& A = s.shapes[a];
        if (s.materials[static_cast<size_t>(A.material)].kind != SceneMaterial::Kind::kMedium)
            continue;
        if (inside_mesh(A.mesh, s.camera.position))
            cam.fail("position", "the camera is inside " + A.name + ", which holds a medium");
        for (std::size_t b = 0; b < s.shapes.size(); ++b) {
            if (b == a) continue;
            const SceneShape& B = s.shapes[b];
            const bool b_medium =
                s.materials[static_cast<size_t>(B.material)].kind == SceneMaterial::Kind::kMedium;
            if (b_medium && b < a) continue;  // that pair was tested from b's side
            if (meshes_overlap(A.mesh, true, B.mesh, b_medium || check_mesh(B.mesh).closed()))
                throw InputError(b > a ? B.where : A.where, b > a ? B.name : A.name,
                                 A.name + " (which holds a medium) and " + B.name +
                                     " intersect or one lies inside the other; move them apart");
        }
    }
    root.finish();
    s.resolved_toml = doc->resolved_toml();
    return s;
}

}  // namespace

std::size_t Scene::triangles() const {
    std::size_t n = 0;
    for (const SceneShape& sh : shapes) n += sh.mesh.triangles.size();
    return n;
}

bool Scene::has_media() const {
    for (const SceneShape& sh : shapes)
        if (materials[static_cast<size_t>(sh.material)].kind == SceneMaterial::Kind::kMedium)
            return true;
    return false;
}

bool Scene::delta_light_through_smooth_boundary() const {
    bool smooth_medium = false;
    for (const SceneShape& sh : shapes) {
        const SceneMaterial& m = materials[static_cast<size_t>(sh.material)];
        // Behind a smooth boundary (roughness 0) light is reached only by chance, unless the
        // boundary is index-matched and the medium homogeneous: the path tracer's shadow rays
        // then cross it (volpath/render.h).
        if (m.kind == SceneMaterial::Kind::kMedium && m.roughness == 0 &&
            (m.medium.eta != 1.0 || !m.density_file.empty()))
            smooth_medium = true;
    }
    if (!smooth_medium) return false;
    for (const SceneLight& l : lights)
        if (Light(l).is_delta()) return true;
    return false;
}

void add_to_key(ContentKey& k, const Scene& s) {
    k.add("scene.name", s.name).add("scene.unit_mm", s.unit_mm);
    k.add("camera.position", s.camera.position);
    k.add("camera.target", s.camera.target);
    k.add("camera.up", s.camera.up);
    k.add("camera.fov_y_deg", s.camera.fov_y_deg)
        .add("camera.width", s.camera.width)
        .add("camera.height", s.camera.height);
    for (std::size_t i = 0; i < s.lights.size(); ++i) {
        add_to_key(k, "lights[" + std::to_string(i) + "].", s.lights[i]);
    }
    for (std::size_t i = 0; i < s.materials.size(); ++i) {
        const SceneMaterial& m = s.materials[i];
        const std::string p = "materials[" + std::to_string(i) + "].";
        k.add(p + "name", m.name);
        if (m.kind == SceneMaterial::Kind::kDiffuse) {
            k.add(p + "type", "diffuse").add(p + "albedo", m.albedo);
            continue;
        }
        k.add(p + "type", "medium");
        add_to_key(k, p, m.medium);
        k.add(p + "roughness", m.roughness);
        if (!m.density_file.empty())
            k.add(p + "density_vdb", file_hash_hex(m.density_file))
                .add(p + "density_grid", m.density_grid);
    }
    for (std::size_t i = 0; i < s.shapes.size(); ++i) {
        const SceneShape& sh = s.shapes[i];
        const std::string p = "shapes[" + std::to_string(i) + "].";
        k.add(p + "name", sh.name).add(p + "type", sh.type).add(p + "material", sh.material);
        // The placed mesh, bytes of its doubles and indices: what the renderers intersect.
        std::string bytes;
        bytes.reserve(sh.mesh.positions.size() * 24 + sh.mesh.triangles.size() * 12);
        for (const Vec3& v : sh.mesh.positions) {
            const double xyz[3] = {v.x == 0 ? 0.0 : v.x, v.y == 0 ? 0.0 : v.y,
                                   v.z == 0 ? 0.0 : v.z};
            bytes.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
        }
        for (const auto& t : sh.mesh.triangles)
            bytes.append(reinterpret_cast<const char*>(t.data()), sizeof(std::uint32_t) * 3);
        k.add(p + "mesh", hash_hex(bytes))
            .add(p + "triangles", static_cast<std::uint64_t>(sh.mesh.triangles.size()))
            .add(p + "exact_sphere", sh.exact_sphere);
        if (sh.exact_sphere) {
            k.add(p + "center", sh.center);
            k.add(p + "radius", sh.radius);
        }
    }
}

Scene read_scene(const std::string& path) {
    return parse(ConfigDocument::parse_file(path), path, fs::path(path).parent_path().string());
}

Scene parse_scene(std::string_view text, const std::string& name, const std::string& base_dir) {
    return parse(ConfigDocument::parse_string(text, name), name, base_dir);
}

std::string describe(const Scene& s) {
    std::string out;
    char buf[512];
    std::snprintf(buf, sizeof buf, "scene %s: 1 unit = %g mm, %zu shapes, %zu triangles\n",
                  s.name.c_str(), s.unit_mm, s.shapes.size(), s.triangles());
    out += buf;
    const SceneCamera& c = s.camera;
    std::snprintf(buf, sizeof buf,
                  "  camera at (%g, %g, %g) looking at (%g, %g, %g), fov %g deg, %d x %d\n",
                  c.position.x, c.position.y, c.position.z, c.target.x, c.target.y, c.target.z,
                  c.fov_y_deg, c.width, c.height);
    out += buf;
    for (const SceneLight& l : s.lights) {
        out += "  light " + describe(l) + "\n";
    }
    for (const SceneMaterial& m : s.materials) {
        if (m.kind == SceneMaterial::Kind::kMedium)
            std::snprintf(
                buf, sizeof buf,
                "  material %s: medium, sigma_a (%g, %g, %g) sigma_s (%g, %g, %g) per mm, eta %g, "
                "roughness %g\n",
                m.name.c_str(), m.medium.sigma_a_per_cm[0] / 10, m.medium.sigma_a_per_cm[1] / 10,
                m.medium.sigma_a_per_cm[2] / 10, m.medium.sigma_s_per_cm[0] / 10,
                m.medium.sigma_s_per_cm[1] / 10, m.medium.sigma_s_per_cm[2] / 10, m.medium.eta,
                m.roughness);
        else
            std::snprintf(buf, sizeof buf, "  material %s: diffuse, albedo (%g, %g, %g)\n",
                          m.name.c_str(), m.albedo[0], m.albedo[1], m.albedo[2]);
        out += buf;
    }
    for (const SceneShape& sh : s.shapes) {
        const auto b = sh.mesh.bounds();
        std::snprintf(
            buf, sizeof buf,
            "  shape %s: %s, material %s, %zu triangles, bounds (%g, %g, %g) - (%g, %g, %g)\n",
            sh.name.c_str(), sh.type.c_str(),
            s.materials[static_cast<size_t>(sh.material)].name.c_str(), sh.mesh.triangles.size(),
            b[0].x, b[0].y, b[0].z, b[1].x, b[1].y, b[1].z);
        out += buf;
    }
    return out;
}

}  // namespace ssslab
