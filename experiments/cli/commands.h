// The subcommands of `ssslab`. Each registers itself on the app and, when chosen, sets `action`.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace ssslab::cli {

void register_mcml(CLI::App& app, std::function<int()>& action);
void register_profile(CLI::App& app, std::function<int()>& action);
void register_sphere(CLI::App& app, std::function<int()>& action);
void register_materials(CLI::App& app, std::function<int()>& action);
void register_scene(CLI::App& app, std::function<int()>& action);
void register_render(CLI::App& app, std::function<int()>& action);
void register_raster(CLI::App& app, std::function<int()>& action);
void register_compare(CLI::App& app, std::function<int()>& action);
void register_bench(CLI::App& app, std::function<int()>& action);
void register_run(CLI::App& app, std::function<int()>& action);
void register_check(CLI::App& app, std::function<int()>& action);

/// Parse and run; returns the exit status. Errors in input: 2; I/O: 3; interrupted: 130.
int main(int argc, char** argv);
/// `main` under mpirun as well (core/distributed.h): what the `ssslab` command runs. A failure on
/// any rank ends all of them with its exit status.
int main_distributed(int argc, char** argv);

}  // namespace ssslab::cli
