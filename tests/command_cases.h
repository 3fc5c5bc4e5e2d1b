// The commands the process-level tests run (tests/test_kill.cpp kills them, tests/test_mpi.cpp
// spreads them over MPI ranks), each with its inputs and the outputs it writes, and how a run's
// outputs are compared with an uninterrupted single-process run's.
#pragma once

#include "testing.h"

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace ssslab::testing {

/// How an output is compared with the reference run's. Files not listed in a case's outputs
/// (provenance, reports) hold timings: they must be complete (the same number of lines); the
/// cache's entries (binary, with timings) are complete when their manifest is there, and are
/// judged by the results made of them and by their estimates: a channel run's result.bin holds
/// the same means and standard errors to the last bit (kEstimates).
enum class Compare { kBytes, kFromLine11, kExrPixels, kLineCount, kPresent, kEstimates };

struct Output {
    std::string path;
    Compare how;
};

struct CommandCase {
    std::string name;
    std::map<std::string, std::string> inputs;
    std::vector<std::string> args;       ///< a short run
    std::vector<std::string> long_args;  ///< a run of about a second
    std::vector<Output> outputs;         ///< compared by content
};

/// Every regular file under `root`, by path relative to it.
std::set<std::string> tree(const std::filesystem::path& root);
/// A temporary (<file>.tmp.<pid>, <dir>.tmp-<pid>, <dir>.old-<pid>) or a checkpoint (*.ckpt*):
/// what a killed run may leave besides finished outputs.
bool transient(const std::string& rel);
/// What a killed run left in `dir`: inputs, temporaries and checkpoints, complete cache entries,
/// and outputs equal to the reference run's (in `whole`).
void expect_nothing_partial(const CommandCase& c, const std::filesystem::path& dir,
                            const std::filesystem::path& whole, const std::string& when);
/// The end: the same files as the reference run, with the same content.
void expect_finished(const CommandCase& c, const std::filesystem::path& dir,
                     const std::filesystem::path& whole, const std::string& when);
void write_inputs(const CommandCase& c, const TempDir& d);
/// `args` with the value after `flag` replaced.
std::vector<std::string> with(std::vector<std::string> args, const std::string& flag,
                              const std::string& value);

/// `ssslab mcml`, `profile` (the path tracer's pencil beam), `render`, `sphere` (the path
/// tracer alone) and `run` (an experiment through the artifact cache), each with --threads 2.
std::vector<CommandCase> command_cases();

}  // namespace ssslab::testing
