// `ssslab compare`: are two Monte Carlo images of one scene the same up to noise? Each side is
// one EXR with a standard-error layer (ssslab render's "radiance" + "radiance.stderr") or K >= 2
// independent runs of a renderer that reports no variance (e.g. Cycles with different seeds), in
// any format OpenImageIO reads (core/image_io.h: EXR, HDR, PNG, TIFF, ...).
// Prints the whole-image means with their standard errors and z per channel, and the per-block
// chi-square (core/image_compare.h); --csv writes every block's z.
#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/film_image.h"
#include "core/hash.h"
#include "core/image_compare.h"
#include "core/image_io.h"
#include "core/provenance.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>

namespace ssslab::cli {

namespace {

namespace fs = std::filesystem;

struct CompareArgs {
    std::vector<std::string> a, b;
    std::string layer_a = "radiance", layer_b = "radiance";
    int block = 16;
    std::string csv;
    std::optional<double> seconds_a, seconds_b;
};

// One side: a single file with <layer>.stderr, or independent runs. A file without the layer
// (Blender writes its combined pass as the default layer R, G, B) is read from the default layer.
ImageEstimate read_side(const std::vector<std::string>& files, const std::string& layer,
                        const char* flag) {
    std::vector<LayeredImage> images;
    for (const std::string& f : files) images.push_back(read_image(f));
    std::string source =
        files[0] +
        (files.size() > 1 ? " + " + std::to_string(files.size() - 1) + " more runs" : "");
    const std::string l = images[0].has_layer(layer) ? layer : "";
    try {
        if (images.size() == 1) return estimate_with_stderr(images[0], l, source);
        return estimate_from_runs(images, l, source);
    } catch (const std::invalid_argument& e) {
        throw InputError({files[0], 0, 0}, flag, e.what());
    }
}

int run_compare(const CompareArgs& a) {
    const ImageEstimate A = read_side(a.a, a.layer_a, "--a");
    const ImageEstimate B = read_side(a.b, a.layer_b, "--b");
    ImageComparison r;
    try {
        r = compare_images(A, B, a.block);
    } catch (const std::invalid_argument& e) {
        throw InputError({a.b[0], 0, 0}, "--b", e.what());
    }
    std::printf("A: %s\nB: %s\n%d x %d pixels, blocks of %d x %d\n", A.source.c_str(),
                B.source.c_str(), A.width, A.height, a.block, a.block);
    std::printf("%-8s %13s %11s %13s %11s %7s %8s %7s %9s\n", "channel", "mean A", "SE A", "mean B",
                "SE B", "z", "blocks", "chi2", "p");
    const char* names[3] = {"R", "G", "B"};
    for (size_t c = 0; c < 3; ++c)
        std::printf("%-8s %13.7g %11.4g %13.7g %11.4g %7.2f %8d %7.1f %9.3g\n", names[c],
                    r.mean_a[c], r.se_a[c], r.mean_b[c], r.se_b[c], r.z_mean[c], r.dof[c],
                    r.chi2[c], r.p[c]);
    std::printf(
        "max |z| of a block %.2f (%d block-channels without variance left out); smallest "
        "p x 3 = %.3g\nrelative RMS difference of block means %.4g (noise alone: %.4g)\n",
        r.max_abs_z, r.skipped, r.p_min_corrected(), r.rel_rms_diff, r.rel_rms_noise);
    if (r.deterministic_differences > 0)
        std::printf("%d block-channels differ where neither image has noise\n",
                    r.deterministic_differences);
    std::array<double, 3> mse_a{}, mse_b{};
    for (int c = 0; c < 3; ++c) {
        mse_a[static_cast<size_t>(c)] = mean_pixel_variance(A, c);
        mse_b[static_cast<size_t>(c)] = mean_pixel_variance(B, c);
    }
    if (a.seconds_a && a.seconds_b) {
        // Efficiency 1 / (MSE x time): the MSE of each side is its mean pixel variance (both are
        // unbiased where the block test passes), the time what it took to render that side.
        std::printf("efficiency 1/(MSE x time), A in %.4g s, B in %.4g s:\n", *a.seconds_a,
                    *a.seconds_b);
        std::printf("%-8s %13s %13s %13s %13s %9s\n", "channel", "MSE A", "MSE B", "eff. A",
                    "eff. B", "A / B");
        for (size_t c = 0; c < 3; ++c) {
            const double ea = 1.0 / (mse_a[c] * *a.seconds_a);
            const double eb = 1.0 / (mse_b[c] * *a.seconds_b);
            std::printf("%-8s %13.4g %13.4g %13.4g %13.4g %9.3g\n", names[c], mse_a[c], mse_b[c],
                        ea, eb, ea / eb);
        }
    }
    if (!a.csv.empty()) {
        std::ostringstream os;
        os << "x0,y0,channel,mean_a,mean_b,se,z\n";
        for (const BlockDifference& d : r.blocks) {
            char buf[200];
            std::snprintf(buf, sizeof buf, "%d,%d,%s,%.9g,%.9g,%.6g,%.4f\n", d.x0, d.y0,
                          names[d.channel], d.a, d.b, d.se, d.z);
            os << buf;
        }
        // Beside it what produced it: the inputs (by content), the settings, the totals.
        auto doc = ConfigDocument::empty("compare.toml");
        ConfigTable root = doc->root();
        ConfigTable in = root.table_or_empty("input");
        for (const auto& [flag, files] : {std::pair{"a", &a.a}, std::pair{"b", &a.b}})
            for (std::size_t i = 0; i < files->size(); ++i) {
                const std::string k = std::string(flag) + "_" + std::to_string(i + 1);
                in.record(k, fs::absolute((*files)[i]).lexically_normal().string());
                in.record(k + "_content_hash", file_hash_hex((*files)[i]));
            }
        in.record("layer_a", a.layer_a);
        in.record("layer_b", a.layer_b);
        in.record("block", static_cast<std::int64_t>(a.block));
        ConfigTable res = root.table_or_empty("result");
        for (size_t c = 0; c < 3; ++c) {
            res.record(std::string("z_mean_") + names[c], r.z_mean[c]);
            res.record(std::string("chi2_") + names[c], r.chi2[c]);
            res.record(std::string("dof_") + names[c], static_cast<std::int64_t>(r.dof[c]));
            res.record(std::string("p_") + names[c], r.p[c]);
            res.record(std::string("mse_a_") + names[c], mse_a[c]);
            res.record(std::string("mse_b_") + names[c], mse_b[c]);
        }
        if (a.seconds_a) in.record("seconds_a", *a.seconds_a);
        if (a.seconds_b) in.record("seconds_b", *a.seconds_b);
        write_with_provenance(
            a.csv, os.str(),
            "ssslab compare: the inputs, settings, result and provenance of " + a.csv, doc);
    }
    return 0;
}

}  // namespace

void register_compare(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<CompareArgs>();
    CLI::App* sub = app.add_subcommand(
        "compare",
        "Compare two Monte Carlo images statistically: image means and per-block z-scores "
        "(each side one EXR with a .stderr layer, or several independent runs)");
    sub->add_option("--a", a->a,
                    "Image A: one EXR with <layer>.stderr, or >= 2 runs (EXR, HDR, PNG, TIFF, ...)")
        ->required()
        ->check(existing_file("image"));
    sub->add_option("--b", a->b,
                    "Image B: one EXR with <layer>.stderr, or >= 2 runs (EXR, HDR, PNG, TIFF, ...)")
        ->required()
        ->check(existing_file("image"));
    sub->add_option("--layer-a", a->layer_a,
                    "Layer of A (default radiance; else the default layer)");
    sub->add_option("--layer-b", a->layer_b,
                    "Layer of B (default radiance; else the default layer)");
    sub->add_option("--block", a->block, "Block size in pixels (default 16)")
        ->check(integer_in(1, 4096));
    sub->add_option("--csv", a->csv, "Write every block's means, SE and z here");
    sub->add_option("--seconds-a", a->seconds_a,
                    "Seconds it took to render A (with --seconds-b: the efficiency "
                    "1/(MSE x time) of both, MSE the mean pixel variance)")
        ->check(positive_number());
    sub->add_option("--seconds-b", a->seconds_b, "Seconds it took to render B (all runs)")
        ->check(positive_number());
    sub->callback([a, &action] { action = [a] { return run_compare(*a); }; });
}

}  // namespace ssslab::cli
