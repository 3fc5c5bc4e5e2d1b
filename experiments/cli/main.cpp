#include "core/error.h"
#include "core/provenance.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"

#include <cstdio>
#include <exception>

namespace ssslab::cli {

int main(int argc, char** argv) {
    set_command_line(argc, argv);
    CLI::App app{
        "ssslab: a research validation framework for subsurface scattering.\n"
        "Monte Carlo ground truth (MCML port) and the approximations renderers use, scored "
        "against it.\nRun `ssslab <command> --help` for each command.",
        "ssslab"};
    app.set_version_flag("--version", version_report());
    app.require_subcommand(0, 1);
    std::function<int()> action;
    register_run(app, action);
    register_check(app, action);
    register_mcml(app, action);
    register_profile(app, action);
    register_sphere(app, action);
    register_materials(app, action);
    register_scene(app, action);
    register_render(app, action);
    register_compare(app, action);
    register_bench(app, action);
    // No command: `run` (the main job; options such as --quick or --dry-run go to it).
    std::vector<std::string> args(argv, argv + argc);
    const bool top_level_flag =
        argc > 1 && (args[1] == "--help" || args[1] == "-h" || args[1] == "--version");
    if (argc == 1 || (args[1].rfind("-", 0) == 0 && !top_level_flag))
        args.insert(args.begin() + 1, "run");
    std::vector<char*> av;
    for (auto& a : args) av.push_back(a.data());
    try {
        app.parse(static_cast<int>(av.size()), av.data());
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    if (!action) return app.exit(CLI::CallForHelp());
    try {
        return action();
    } catch (const InputError& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 2;
    } catch (const InfeasibleError& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    } catch (const IoError& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 3;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "internal error: %s\n", e.what());
        return 1;
    }
}

}  // namespace ssslab::cli

int main(int argc, char** argv) {
    return ssslab::cli::main(argc, argv);
}
