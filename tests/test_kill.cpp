// kill -9 anywhere (issue 17). A command killed at any point -- at each crash point on the way
// to its outputs in turn (core/crash_point.h: a temporary half written, whole, renamed; a
// transaction's renames; a cache entry staged; a results directory swapped in), or at random
// times while it computes and checkpoints -- must leave nothing under an output's name that the
// uninterrupted run would not write there (a half-written or stale file), and the same command
// run again must end with the uninterrupted run's outputs bit for bit and no litter: no
// temporary, no checkpoint, no stray file.
//
// Cases: `ssslab mcml`, `profile` (the path tracer's pencil beam), `render` and `run` (an
// experiment through the artifact cache). The default variant kills at a dozen crash points
// spread over each command's sequence (threads may reorder them: which ones are hit varies) and
// at random times until three kills are made; slow.* (SSSLAB_TEST_SCALE=10) at every crash
// point and until twenty kills.
#include "core/film_image.h"
#include "testing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab {
namespace {

namespace fs = std::filesystem;

/// How an output is compared with the uninterrupted run's. Files not listed in a case's outputs
/// (provenance, reports) hold timings: they must be complete (the same number of lines); the
/// cache's entries (binary, with timings) are complete when their manifest is there, and are
/// judged by the results made of them.
enum class Compare { kBytes, kFromLine11, kExrPixels, kLineCount, kPresent };

struct Output {
    std::string path;
    Compare how;
};

struct KillCase {
    std::string name;
    std::map<std::string, std::string> inputs;
    std::vector<std::string> args;       ///< a short run, killed at each crash point in turn
    std::vector<std::string> long_args;  ///< a run of about a second, killed at random times
    std::vector<Output> outputs;         ///< compared by content
};

/// Every regular file under `root`, by path relative to it.
std::set<std::string> tree(const fs::path& root) {
    std::set<std::string> out;
    for (const auto& e : fs::recursive_directory_iterator(root))
        if (e.is_regular_file()) out.insert(fs::relative(e.path(), root).string());
    return out;
}

/// A temporary (<file>.tmp.<pid>, <dir>.tmp-<pid>, <dir>.old-<pid>) or a checkpoint (*.ckpt*):
/// what a killed run may leave besides finished outputs.
bool transient(const std::string& rel) {
    for (const auto& part : fs::path(rel)) {
        const std::string p = part.string();
        if (p.find(".tmp.") != std::string::npos || p.find(".tmp-") != std::string::npos ||
            p.rfind(".tmp-", 0) == 0 || p.find(".old-") != std::string::npos ||
            p.find(".ckpt") != std::string::npos)
            return true;
    }
    return false;
}

size_t count_lines(const std::string& s) {
    return static_cast<size_t>(std::count(s.begin(), s.end(), '\n'));
}

/// Whether file `rel` in `dir` holds what the uninterrupted run wrote there (in `whole`);
/// otherwise a description of the difference.
std::string difference(const fs::path& dir, const fs::path& whole, const std::string& rel,
                       Compare how) {
    const fs::path a = dir / rel, b = whole / rel;
    if (how == Compare::kExrPixels) {
        const LayeredImage x = read_exr(a.string()), y = read_exr(b.string());
        if (x.layers().size() != y.layers().size()) return "a different number of layers";
        for (const auto& l : y.layers()) {
            if (!x.has_layer(l.name())) return "no layer " + l.name();
            const auto px = x.layer(l.name()).pixels(), py = l.pixels();
            if (!std::equal(px.begin(), px.end(), py.begin(), py.end()))
                return "layer " + l.name() + " differs";
        }
        return {};
    }
    if (how == Compare::kPresent) return {};
    const std::string x = testing::read_text(a), y = testing::read_text(b);
    switch (how) {
        case Compare::kBytes:
            return x == y ? "" : "different bytes";
        case Compare::kFromLine11:
            return testing::lines_from(x, 11) == testing::lines_from(y, 11)
                       ? ""
                       : "different content from line 11";
        default:
            return count_lines(x) == count_lines(y) && !x.empty() && x.back() == y.back()
                       ? ""
                       : std::to_string(count_lines(x)) + " lines, the uninterrupted run's " +
                             std::to_string(count_lines(y));
    }
}

Compare rule(const KillCase& c, const std::string& rel) {
    for (const auto& o : c.outputs)
        if (o.path == rel) return o.how;
    return rel.rfind("results/cache/", 0) == 0 ? Compare::kPresent : Compare::kLineCount;
}

/// What a killed run left in `dir`: inputs, temporaries and checkpoints, complete cache entries,
/// and outputs equal to the uninterrupted run's (in `whole`).
void expect_nothing_partial(const KillCase& c, const fs::path& dir, const fs::path& whole,
                            const std::string& when) {
    const std::set<std::string> expected = tree(whole);
    for (const std::string& rel : tree(dir)) {
        if (c.inputs.count(rel) || transient(rel)) continue;
        if (!expected.count(rel)) {
            ADD_FAILURE() << when << ": '" << rel << "' is no output of the uninterrupted run";
            continue;
        }
        const std::string d = difference(dir, whole, rel, rule(c, rel));
        EXPECT_TRUE(d.empty()) << when << ": '" << rel << "' is visible with " << d;
    }
    const fs::path cache = dir / "results" / "cache";
    if (fs::exists(cache))
        for (const auto& kind : fs::directory_iterator(cache))
            for (const auto& e : fs::directory_iterator(kind.path())) {
                const std::string n = e.path().filename().string();
                if (e.is_directory() && !transient(n)) {
                    EXPECT_TRUE(fs::exists(e.path() / "manifest.toml"))
                        << when << ": a partial cache entry " << n;
                }
            }
}

/// The end: the same files as the uninterrupted run, with the same content.
void expect_finished(const KillCase& c, const fs::path& dir, const fs::path& whole,
                     const std::string& when) {
    std::set<std::string> have = tree(dir);
    for (const auto& [name, content] : c.inputs) have.erase(name);
    std::set<std::string> want = tree(whole);
    for (const auto& [name, content] : c.inputs) want.erase(name);
    EXPECT_EQ(have, want) << when;
    for (const std::string& rel : want)
        if (have.count(rel)) {
            const std::string d = difference(dir, whole, rel, rule(c, rel));
            EXPECT_TRUE(d.empty()) << when << ": '" << rel << "' ends with " << d;
        }
}

void write_inputs(const KillCase& c, const testing::TempDir& d) {
    for (const auto& [name, content] : c.inputs) d.write(name, content);
}

/// The crash points an uninterrupted run passes, in order.
std::vector<std::string> crash_points(const KillCase& c, const testing::TempDir& whole) {
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
void kill_at_crash_points(const KillCase& c, bool every) {
    SCOPED_TRACE(c.name);
    testing::TempDir whole;
    write_inputs(c, whole);
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
        write_inputs(c, dir);
        ::setenv("SSSLAB_CRASH_AT", std::to_string(k).c_str(), 1);
        const auto killed = testing::run_ssslab(c.args, dir.path());
        ::unsetenv("SSSLAB_CRASH_AT");
        // The points threads pass may come in another order; the k-th is some point all the same.
        ASSERT_EQ(killed.exit_code, 128 + SIGKILL) << when << "\n" << killed.err;
        expect_nothing_partial(c, dir.path(), whole.path(), when);
        const auto again = testing::run_ssslab(c.args, dir.path());
        ASSERT_EQ(again.exit_code, 0) << when << "\n" << again.err;
        expect_finished(c, dir.path(), whole.path(), when + ", then run again");
    }
    std::printf("%s: killed at %zu of its %zu crash points\n", c.name.c_str(), at.size(), n);
}

/// Kill the long run of `c` at random times (checkpoints every 20 ms) until it finishes, and
/// again from the start in a fresh directory, until `kills` kills have been made.
void kill_at_random_times(const KillCase& c, int kills, unsigned seed) {
    SCOPED_TRACE(c.name);
    testing::TempDir whole;
    write_inputs(c, whole);
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
        write_inputs(c, dir);
        for (int k = 1;; ++k) {
            const int after = static_cast<int>(delay(rng));
            const int rc = testing::run_and_kill(c.long_args, dir.path(), after, SIGKILL);
            const std::string when = "run " + std::to_string(chains) + ", kill " +
                                     std::to_string(k) + " after " + std::to_string(after) + " ms";
            if (rc == 0) {
                expect_finished(c, dir.path(), whole.path(), when + " (it had finished)");
                break;
            }
            ASSERT_EQ(rc, 128 + SIGKILL) << when;
            ++killed;
            expect_nothing_partial(c, dir.path(), whole.path(), when);
        }
    }
    ::unsetenv("SSSLAB_CHECKPOINT_SECONDS");
    std::printf("%s: %d kills in %d runs to the end (an uninterrupted run %.0f ms)\n",
                c.name.c_str(), killed, chains, ms);
}

std::vector<std::string> with(std::vector<std::string> args, const std::string& flag,
                              const std::string& value) {
    *(std::find(args.begin(), args.end(), flag) + 1) = value;
    return args;
}

KillCase mcml_case() {
    KillCase c;
    c.name = "mcml";
    c.inputs["b.mci"] = testing::read_text(testing::data_path("mcml-1.2.2/b_giov_n15.mci"));
    c.args = {"mcml", "b.mci", "--photons", "20000", "--batch", "2000", "--threads", "2", "-q"};
    c.long_args = with(c.args, "--photons", "3000000");
    c.outputs = {{"b_giov_n15.mco", Compare::kFromLine11},
                 {"b_giov_n15_stderr.mco", Compare::kFromLine11}};
    return c;
}

KillCase profile_case() {
    KillCase c;
    c.name = "profile";
    c.inputs["c.toml"] = "[material]\npreset = \"Skin1\"\n";
    c.args = {"profile", "--config",  "c.toml", "--photons", "20000", "--batch",
              "2000",    "--threads", "2",      "--out",     "p.csv", "-q"};
    c.long_args = with(c.args, "--photons", "600000");
    c.outputs = {{"p.csv", Compare::kBytes}};
    return c;
}

KillCase render_case() {
    KillCase c;
    c.name = "render";
    c.inputs["s.toml"] = testing::ball_scene(30, 24, 16);
    c.args = {"render",    "s.toml", "--spp", "18",    "--batch-spp", "6",
              "--threads", "2",      "--out", "m.exr", "-q"};
    c.long_args = with(c.args, "--spp", "3000");
    c.outputs = {{"m.exr", Compare::kExrPixels}, {"m.png", Compare::kBytes}};
    return c;
}

KillCase run_case() {
    KillCase c;
    c.name = "run";
    c.inputs["small.toml"] = testing::kSmallExperiment;
    c.args = {"run", "small.toml", "--threads", "2", "-q"};
    c.inputs["big.toml"] = testing::kSmallExperiment;
    std::string big = testing::kSmallExperiment;
    big.replace(big.find("photons = 20000"), 15, "photons = 300000");
    c.inputs["big.toml"] = big;
    c.long_args = {"run", "big.toml", "--threads", "2", "-q"};
    for (const char* f : {"profiles/Skin1.csv", "profiles/Slab.csv", "summary.csv", "metrics.csv"})
        c.outputs.push_back({std::string("results/small/") + f, Compare::kBytes});
    return c;
}

std::vector<KillCase> cases() {
    return {mcml_case(), profile_case(), render_case(), run_case()};
}

bool slow() {
    return testing::test_scale() > 1;
}

TEST(KillAnywhere, AtEachCrashPointNothingPartialIsVisibleAndARerunFinishesTheSame) {
    for (const KillCase& c : cases()) kill_at_crash_points(c, slow());
}

TEST(KillAnywhere, AtRandomTimesTheResumedRunEqualsTheUninterruptedOne) {
    unsigned seed = 17;
    for (const KillCase& c : cases()) kill_at_random_times(c, slow() ? 20 : 3, seed++);
}

}  // namespace
}  // namespace ssslab
