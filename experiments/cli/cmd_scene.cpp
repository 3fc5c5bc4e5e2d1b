// `ssslab scene`: read and validate scene files (core/scene.h) and describe them; optionally
// export every shape's tessellation as OBJ in world units (for other renderers, e.g. Blender).
#include "core/atomic_file.h"
#include "core/scene.h"
#include "experiments/cli/commands.h"

#include <cstdio>
#include <filesystem>

namespace ssslab::cli {

namespace {

struct SceneArgs {
    std::vector<std::string> files;
    std::string export_dir;
};

int run_scene(const SceneArgs& a) {
    // All scenes are read before anything is written: a bad one leaves no output.
    std::vector<Scene> scenes;
    for (const std::string& f : a.files) scenes.push_back(read_scene(f));
    for (const Scene& s : scenes) std::printf("%s", describe(s).c_str());
    if (!a.export_dir.empty()) {
        OutputTransaction out;
        for (const Scene& s : scenes)
            for (const SceneShape& sh : s.shapes) {
                std::string name = sh.name;
                for (char& c : name)
                    if (c == '[' || c == ']' || c == '/' || c == ' ') c = '_';
                out.stage(std::filesystem::path(a.export_dir) / s.name / (name + ".obj"),
                          to_obj(sh.mesh));
            }
        out.commit();
        std::printf("exported the shapes' meshes (world units) to %s/<scene>/\n",
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
    sub->add_option("files", a->files, "Scene files (TOML)")->required()->check(CLI::ExistingFile);
    sub->add_option("--export-obj", a->export_dir,
                    "Write every shape's tessellation, placed in world units, as "
                    "<dir>/<scene>/<shape>.obj");
    sub->callback([a, &action] { action = [a] { return run_scene(*a); }; });
}

}  // namespace ssslab::cli
