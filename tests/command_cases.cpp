#include "command_cases.h"

#include "core/batch_runner.h"
#include "core/film_image.h"
#include "mcml/engine.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace ssslab::testing {

namespace fs = std::filesystem;

namespace {

size_t count_lines(const std::string& s) {
    return static_cast<size_t>(std::count(s.begin(), s.end(), '\n'));
}

}  // namespace

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

namespace {

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
    if (how == Compare::kEstimates) {
        // results/cache/<kind>/<key>/result.bin of an MCML or a path-tracer channel run.
        const std::string kind = fs::path(rel).parent_path().parent_path().filename().string();
        const std::string x = read_text(a), y = read_text(b);
        if (kind == "mcml-channel") {
            const mcml::RunResult p = mcml::deserialize_result(x, a.string()),
                                  q = mcml::deserialize_result(y, b.string());
            if (p.values != q.values || p.divisor != q.divisor || p.se != q.se)
                return "other estimates";
            return p.photons == q.photons && p.events == q.events ? "" : "other counts";
        }
        const BatchRunResult p = deserialize_batch_result(x, a.string()),
                             q = deserialize_batch_result(y, b.string());
        if (p.mean != q.mean || p.se != q.se) return "other estimates";
        return p.samples == q.samples && p.work == q.work ? "" : "other counts";
    }
    const std::string x = read_text(a), y = read_text(b);
    switch (how) {
        case Compare::kBytes:
            return x == y ? "" : "different bytes";
        case Compare::kFromLine11:
            return lines_from(x, 11) == lines_from(y, 11) ? "" : "different content from line 11";
        default:
            return count_lines(x) == count_lines(y) && !x.empty() && x.back() == y.back()
                       ? ""
                       : std::to_string(count_lines(x)) + " lines, the uninterrupted run's " +
                             std::to_string(count_lines(y));
    }
}

Compare rule(const CommandCase& c, const std::string& rel) {
    for (const auto& o : c.outputs)
        if (o.path == rel) return o.how;
    if (rel.rfind("results/cache/", 0) != 0) return Compare::kLineCount;
    const bool channel = rel.find("/mcml-channel/") != std::string::npos ||
                         rel.find("/volpath-channel/") != std::string::npos;
    return channel && fs::path(rel).filename() == "result.bin" ? Compare::kEstimates
                                                               : Compare::kPresent;
}

}  // namespace

/// What a killed run left in `dir`: inputs, temporaries and checkpoints, complete cache entries,
/// and outputs equal to the uninterrupted run's (in `whole`).
void expect_nothing_partial(const CommandCase& c, const fs::path& dir, const fs::path& whole,
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
void expect_finished(const CommandCase& c, const fs::path& dir, const fs::path& whole,
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

void write_inputs(const CommandCase& c, const TempDir& d) {
    for (const auto& [name, content] : c.inputs) d.write(name, content);
}

std::vector<std::string> with(std::vector<std::string> args, const std::string& flag,
                              const std::string& value) {
    *(std::find(args.begin(), args.end(), flag) + 1) = value;
    return args;
}

namespace {

CommandCase mcml_case() {
    CommandCase c;
    c.name = "mcml";
    c.inputs["b.mci"] = read_text(data_path("mcml-1.2.2/b_giov_n15.mci"));
    c.args = {"mcml", "b.mci", "--photons", "20000", "--batch", "2000", "--threads", "2", "-q"};
    c.long_args = with(c.args, "--photons", "3000000");
    c.outputs = {{"b_giov_n15.mco", Compare::kFromLine11},
                 {"b_giov_n15_stderr.mco", Compare::kFromLine11}};
    return c;
}

CommandCase profile_case() {
    CommandCase c;
    c.name = "profile";
    c.inputs["c.toml"] = "[material]\npreset = \"Skin1\"\n";
    c.args = {"profile", "--config",  "c.toml", "--photons", "20000", "--batch",
              "2000",    "--threads", "2",      "--out",     "p.csv", "-q"};
    c.long_args = with(c.args, "--photons", "600000");
    c.outputs = {{"p.csv", Compare::kBytes}};
    return c;
}

CommandCase render_case() {
    CommandCase c;
    c.name = "render";
    c.inputs["s.toml"] = ball_scene(30, 24, 16);
    c.args = {"render",    "s.toml", "--spp", "18",    "--batch-spp", "6",
              "--threads", "2",      "--out", "m.exr", "-q"};
    c.long_args = with(c.args, "--spp", "3000");
    c.outputs = {{"m.exr", Compare::kExrPixels}, {"m.png", Compare::kBytes}};
    return c;
}

CommandCase sphere_case() {
    CommandCase c;
    c.name = "sphere";
    c.args = {"sphere",   "-m",   "Skin1",     "--photons", "60000", "--size", "24",
              "--models", "none", "--threads", "2",         "--out", "s/s",    "-q"};
    c.long_args = with(c.args, "--photons", "1500000");
    c.outputs = {{"s/s.exr", Compare::kExrPixels},
                 {"s/s.png", Compare::kBytes},
                 {"s/s_beta.csv", Compare::kBytes}};
    return c;
}

CommandCase run_case() {
    CommandCase c;
    c.name = "run";
    c.inputs["small.toml"] = kSmallExperiment;
    c.args = {"run", "small.toml", "--threads", "2", "-q"};
    c.inputs["big.toml"] = kSmallExperiment;
    std::string big = kSmallExperiment;
    big.replace(big.find("photons = 20000"), 15, "photons = 300000");
    c.inputs["big.toml"] = big;
    c.long_args = {"run", "big.toml", "--threads", "2", "-q"};
    for (const char* f : {"profiles/Skin1.csv", "profiles/Slab.csv", "summary.csv", "metrics.csv"})
        c.outputs.push_back({std::string("results/small/") + f, Compare::kBytes});
    return c;
}

}  // namespace

std::vector<CommandCase> command_cases() {
    return {mcml_case(), profile_case(), render_case(), sphere_case(), run_case()};
}

}  // namespace ssslab::testing
