// kill -9 anywhere (issue 17). A command killed at any point -- at each crash point on the way
// to its outputs in turn (core/crash_point.h: a temporary half written, whole, renamed; a
// transaction's renames; a cache entry staged; a results directory swapped in), or at random
// times while it computes and checkpoints -- must leave nothing under an output's name that the
// uninterrupted run would not write there (a half-written or stale file), and the same command
// run again must end with the uninterrupted run's outputs bit for bit and no litter: no
// temporary, no checkpoint, no stray file.
//
// Cases (tests/command_cases.h): `ssslab mcml`, `profile` (the path tracer's pencil beam),
// `render`, `sphere` and `run` (an experiment through the artifact cache). The default variant
// kills at a dozen crash points spread over each command's sequence (threads may reorder them:
// which ones are hit varies) and at random times until three kills are made; slow.*
// (SSSLAB_TEST_SCALE=10) at every crash point and until twenty kills.
#include "command_cases.h"
#include "testing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab {
namespace {

namespace fs = std::filesystem;
using testing::CommandCase;

/// The crash points an uninterrupted run passes, in order.
std::vector<std::string> crash_points(const CommandCase& c, const testing::TempDir& whole) {
    testing::TempDir logs;
    const fs::path log = logs / "points";
    ::setenv("SSSLAB_CRASH_LOG", log.c_str(), 1);
    const auto r = testing::run_ssslab(c.args, whole.path());
    ::unsetenv("SSSLAB_CRASH_LOG");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::vector<std::string> names;
    if (!fs::exists(log)) return names;
    std::istringstream in(testing::read_text(log));
    std::string n, name;
    while (in >> n >> name) names.push_back(name);
    return names;
}

/// Kill `c` at crash points (all with `every`, else about a dozen spread over the sequence), and
/// after each run it again to the end.
void kill_at_crash_points(const CommandCase& c, bool every) {
    SCOPED_TRACE(c.name);
    testing::TempDir whole;
    testing::write_inputs(c, whole);
    const std::vector<std::string> points = crash_points(c, whole);
    ASSERT_GE(points.size(), 3u) << "the run passes too few crash points to test";
    const size_t n = points.size();
    std::vector<size_t> at;
    const size_t step = every ? 1 : std::max<size_t>(1, n / 12);
    for (size_t k = 1; k <= n; k += step) at.push_back(k);
    if (at.empty() || at.back() != n)
        at.push_back(n);  // the last point: after every output is in place
    for (const size_t k : at) {
        const std::string when = "killed at crash point " + std::to_string(k) + " of " +
                                 std::to_string(n) + " (" + points[k - 1] + ")";
        testing::TempDir dir;
        testing::write_inputs(c, dir);
        ::setenv("SSSLAB_CRASH_AT", std::to_string(k).c_str(), 1);
        const auto killed = testing::run_ssslab(c.args, dir.path());
        ::unsetenv("SSSLAB_CRASH_AT");
        // The points threads pass may come in another order; the k-th is some point all the same.
        ASSERT_EQ(killed.exit_code, 128 + SIGKILL) << when << "\n" << killed.err;
        testing::expect_nothing_partial(c, dir.path(), whole.path(), when);
        const auto again = testing::run_ssslab(c.args, dir.path());
        ASSERT_EQ(again.exit_code, 0) << when << "\n" << again.err;
        testing::expect_finished(c, dir.path(), whole.path(), when + ", then run again");
    }
    std::printf("%s: killed at %zu of its %zu crash points\n", c.name.c_str(), at.size(), n);
}

/// Kill the long run of `c` at random times (checkpoints every 20 ms) until it finishes, and
/// again from the start in a fresh directory, until `kills` kills have been made.
void kill_at_random_times(const CommandCase& c, int kills, unsigned seed) {
    SCOPED_TRACE(c.name);
    testing::TempDir whole;
    testing::write_inputs(c, whole);
    const auto t0 = std::chrono::steady_clock::now();
    const auto full = testing::run_ssslab(c.long_args, whole.path());
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_EQ(full.exit_code, 0) << full.err;

    ::setenv("SSSLAB_CHECKPOINT_SECONDS", "0.02", 1);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> delay(0.0, 1.1 * ms);
    int killed = 0, chains = 0;
    while (killed < kills && !::testing::Test::HasFatalFailure()) {
        ++chains;
        testing::TempDir dir;
        testing::write_inputs(c, dir);
        for (int k = 1;; ++k) {
            const int after = static_cast<int>(delay(rng));
            const int rc = testing::run_and_kill(c.long_args, dir.path(), after, SIGKILL);
            const std::string when = "run " + std::to_string(chains) + ", kill " +
                                     std::to_string(k) + " after " + std::to_string(after) + " ms";
            if (rc == 0) {
                testing::expect_finished(c, dir.path(), whole.path(), when + " (it had finished)");
                break;
            }
            ASSERT_EQ(rc, 128 + SIGKILL) << when;
            ++killed;
            testing::expect_nothing_partial(c, dir.path(), whole.path(), when);
        }
    }
    ::unsetenv("SSSLAB_CHECKPOINT_SECONDS");
    std::printf("%s: %d kills in %d runs to the end (an uninterrupted run %.0f ms)\n",
                c.name.c_str(), killed, chains, ms);
}

bool slow() {
    return testing::test_scale() > 1;
}

TEST(KillAnywhere, AtEachCrashPointNothingPartialIsVisibleAndARerunFinishesTheSame) {
    for (const CommandCase& c : testing::command_cases()) kill_at_crash_points(c, slow());
}

TEST(KillAnywhere, AtRandomTimesTheResumedRunEqualsTheUninterruptedOne) {
    unsigned seed = 17;
    for (const CommandCase& c : testing::command_cases())
        kill_at_random_times(c, slow() ? 20 : 3, seed++);
}

}  // namespace
}  // namespace ssslab
