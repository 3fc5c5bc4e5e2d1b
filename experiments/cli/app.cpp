// The `ssslab` command line: every subcommand on one CLI11 app, bad input as exit status 2, MPI
// ranks set up and torn down. In the ssslab_cli library, so a program built against ssslab (e.g.
// examples/custom_model/, which adds a model first) is the same command.
#include "core/atomic_file.h"
#include "core/distributed.h"
#include "core/error.h"
#include "core/provenance.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"

#include <cstdio>
#include <exception>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab::cli {

namespace {

// A bad command line is bad input like any other: exit 2 with one readable line on stderr,
// "ssslab render: error: --spp: must be a positive integer, got 0" (CLI11's own exit codes, 105 and
// so on, and its help text are left out).
int command_line_error(CLI::App& app, const CLI::ParseError& e) {
    std::string command = "ssslab";
    const CLI::App* sub = nullptr;
    for (const CLI::App* s : app.get_subcommands()) {
        command += " " + s->get_name();
        sub = s;
    }
    std::string message = e.what();
    // A positional argument's check says what it is ("scene file 'x.toml' does not exist"):
    // CLI11's "scene: " in front of it adds nothing.
    if (sub && dynamic_cast<const CLI::ValidationError*>(&e))
        for (const CLI::Option* o : sub->get_options())
            if (o->get_positional() && message.rfind(o->get_name() + ": ", 0) == 0) {
                message = message.substr(o->get_name().size() + 2);
                break;
            }
    if (dynamic_cast<const CLI::ExtrasError*>(&e)) {
        // CLI11 lists the extra arguments in reverse ("... not expected: 3 --photons").
        const size_t colon = message.find(": ");
        std::vector<std::string> words;
        if (colon != std::string::npos) {
            std::istringstream in(message.substr(colon + 2));
            for (std::string w; in >> w;) words.insert(words.begin(), w);
        }
        if (!words.empty()) {
            std::string extras;
            for (const std::string& w : words) extras += (extras.empty() ? "" : " ") + w;
            message =
                std::string(words.size() > 1 ? "unexpected arguments: " : "unexpected argument: ") +
                extras +
                (words[0].rfind("-", 0) == 0
                     ? " (" + words[0] + " is not an option of " + command + ")"
                     : std::string());
        }
    }
    if (dist::is_root())  // every rank of an MPI run parses the same command line
        std::fprintf(stderr, "%s: error: %s\nRun `%s --help` for the options.\n", command.c_str(),
                     message.c_str(), command.c_str());
    return 2;
}

}  // namespace

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
    register_raster(app, action);
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
        if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success))
            return app.exit(e);  // --help, --version
        return command_line_error(app, e);
    }
    if (!action) return app.exit(CLI::CallForHelp());
    // Bad input is the same on every rank of an MPI run: rank 0 says it. Any other error may be
    // one rank's own, so that rank says it.
    const bool say_input = dist::is_root();
    const std::string rank_tag =
        dist::active() ? "[rank " + std::to_string(dist::rank()) + "] " : "";
    try {
        return action();
    } catch (const InputError& e) {
        if (say_input) std::fprintf(stderr, "%s\n", e.what());
        return 2;
    } catch (const InfeasibleError& e) {
        if (say_input) std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    } catch (const IoError& e) {
        std::fprintf(stderr, "%serror: %s\n", rank_tag.c_str(), e.what());
        return 3;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%sinternal error: %s\n", rank_tag.c_str(), e.what());
        return 1;
    }
}

/// Under mpirun (core/distributed.h): MPI started, rank 0 writes the outputs and the report on
/// stdout, the other ranks compute with it and write nothing. A failure on any rank ends all
/// of them with its exit status (the others would wait for the failed one forever).
int main_distributed(int argc, char** argv) {
    std::optional<dist::Session> session;
    try {
        session.emplace(argc, argv);
    } catch (const InputError& e) {
        std::fprintf(stderr, "ssslab: error: %s\n", e.message().c_str());
        return 2;
    }
    if (!dist::is_root()) {
        if (!std::freopen("/dev/null", "w", stdout)) std::fclose(stdout);
        discard_outputs(true);
    }
    const int status = main(argc, argv);
    if (status != 0 && dist::active()) {
        std::fflush(stdout);
        std::fflush(stderr);
        dist::abort_all(status);
    }
    return status;
}

}  // namespace ssslab::cli
