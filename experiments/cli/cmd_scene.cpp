// `ssslab scene`: read and validate scene files (core/scene.h) and describe them; optionally
// export every shape's tessellation as OBJ in world units, with scene.json: the camera, lights
// and materials in world units, for another renderer to rebuild the scene (scripts/cycles_render.py
// does so in Blender's Cycles for the side-by-side of README "Ground truth against Cycles").
#include "core/atomic_file.h"
#include "core/format.h"
#include "core/hash.h"
#include "core/provenance.h"
#include "core/scene.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"

#include <cstdio>
#include <filesystem>
#include <sstream>

namespace ssslab::cli {

namespace {

struct SceneArgs {
    std::vector<std::string> files;
    std::string export_dir;
};

std::string file_name(std::string name) {
    for (char& c : name)
        if (c == '[' || c == ']' || c == '/' || c == ' ') c = '_';
    return name + ".obj";
}

std::string json_string(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') o += '\\';
        if (static_cast<unsigned char>(c) < 0x20) continue;
        o += c;
    }
    return o + "\"";
}

std::string vec(const Vec3& v) {
    return "[" + format_g(v.x, 17) + ", " + format_g(v.y, 17) + ", " + format_g(v.z, 17) + "]";
}
std::string rgb(const std::array<double, 3>& v) {
    return "[" + format_g(v[0], 17) + ", " + format_g(v[1], 17) + ", " + format_g(v[2], 17) + "]";
}

// The scene in world units, for other renderers: media coefficients per world unit, the
// boundary's GGX alpha, lights in the units of core/scene.h (directional: irradiance facing the
// light and the disc's angular radius; sphere/environment: radiance; point and spot: intensity).
std::string scene_json(const Scene& s) {
    std::ostringstream o;
    const SceneCamera& c = s.camera;
    o << "{\n  \"scene\": " << json_string(s.name)
      << ",\n  \"unit_mm\": " << format_g(s.unit_mm, 17)
      << ",\n  \"camera\": {\"position\": " << vec(c.position) << ", \"target\": " << vec(c.target)
      << ", \"up\": " << vec(c.up) << ", \"fov_y_deg\": " << format_g(c.fov_y_deg, 17)
      << ", \"width\": " << c.width << ", \"height\": " << c.height << "},\n  \"lights\": [";
    for (std::size_t i = 0; i < s.lights.size(); ++i) {
        const SceneLight& l = s.lights[i];
        o << (i ? "," : "") << "\n    {\"type\": " << json_string(to_string(l.type));
        o << json_members(l);
        o << "}";
    }
    o << "\n  ],\n  \"materials\": [";
    for (std::size_t i = 0; i < s.materials.size(); ++i) {
        const SceneMaterial& m = s.materials[i];
        o << (i ? "," : "") << "\n    {\"name\": " << json_string(m.name);
        if (m.kind == SceneMaterial::Kind::kDiffuse) {
            o << ", \"type\": \"diffuse\", \"albedo\": " << rgb(m.albedo) << "}";
            continue;
        }
        std::array<double, 3> sa{}, ss{};
        for (int k = 0; k < 3; ++k) {
            sa[static_cast<size_t>(k)] =
                s.per_world_unit(m.medium.sigma_a_per_cm[static_cast<size_t>(k)]);
            ss[static_cast<size_t>(k)] =
                s.per_world_unit(m.medium.sigma_s_per_cm[static_cast<size_t>(k)]);
        }
        o << ", \"type\": \"medium\", \"sigma_a_per_unit\": " << rgb(sa)
          << ", \"sigma_s_per_unit\": " << rgb(ss) << ", \"g\": " << rgb(m.medium.g)
          << ", \"eta\": " << format_g(m.medium.eta, 17)
          << ", \"ggx_alpha\": " << format_g(m.roughness, 17);
        if (!m.density_file.empty())
            o << ", \"density_vdb\": " << json_string(m.density_file)
              << ", \"density_grid\": " << json_string(m.density_grid);
        o << "}";
    }
    o << "\n  ],\n  \"shapes\": [";
    for (std::size_t i = 0; i < s.shapes.size(); ++i) {
        const SceneShape& sh = s.shapes[i];
        o << (i ? "," : "") << "\n    {\"name\": " << json_string(sh.name)
          << ", \"obj\": " << json_string(file_name(sh.name))
          << ", \"material\": " << json_string(s.materials[static_cast<size_t>(sh.material)].name)
          << "}";
    }
    // What produced the export: the scene file, its content key, ssslab's provenance.
    ContentKey key("scene");
    add_to_key(key, s);
    o << "\n  ],\n  \"source\": " << json_string(s.path)
      << ",\n  \"content_key\": " << json_string(key.hex()) << ",\n  \"provenance\": {";
    const auto pv = provenance(command_line());
    for (std::size_t i = 0; i < pv.size(); ++i)
        o << (i ? ", " : "") << json_string(pv[i].first) << ": " << json_string(pv[i].second);
    o << "}\n}\n";
    return o.str();
}

int run_scene(const SceneArgs& a) {
    // All scenes are read before anything is written: a bad one leaves no output.
    std::vector<Scene> scenes;
    for (const std::string& f : a.files) scenes.push_back(read_scene(f));
    for (const Scene& s : scenes) std::printf("%s", describe(s).c_str());
    if (!a.export_dir.empty()) {
        OutputTransaction out;
        for (const Scene& s : scenes) {
            const std::filesystem::path dir = std::filesystem::path(a.export_dir) / s.name;
            for (const SceneShape& sh : s.shapes)
                out.stage(dir / file_name(sh.name), to_obj(sh.mesh));
            out.stage(dir / "scene.json", scene_json(s));
        }
        out.commit();
        std::printf("exported the shapes' meshes (world units) and scene.json to %s/<scene>/\n",
                    a.export_dir.c_str());
    }
    return 0;
}

}  // namespace

void register_scene(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<SceneArgs>();
    CLI::App* sub = app.add_subcommand(
        "scene",
        "Read and validate scene files (camera, lights, materials, shapes) and describe "
        "them; errors name file, line and key");
    sub->add_option("files", a->files, "Scene files (TOML)")
        ->required()
        ->check(existing_file("scene file"));
    sub->add_option("--export-obj", a->export_dir,
                    "Write every shape's tessellation, placed in world units, as "
                    "<dir>/<scene>/<shape>.obj, and <dir>/<scene>/scene.json (camera, lights, "
                    "materials per world unit) for other renderers");
    sub->callback([a, &action] { action = [a] { return run_scene(*a); }; });
}

}  // namespace ssslab::cli
