// The experiment runner: content keys, cache reuse, interruption and resumption, config errors,
// regression checks, and the report in a headless browser.
#include "core/build_info.h"
#include "core/film_image.h"
#include "experiments/runner/experiment.h"
#include "experiments/runner/plots.h"
#include "experiments/runner/report.h"
#include "experiments/runner/runner.h"
#include "testing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

namespace ssslab {
namespace {

namespace fs = std::filesystem;
using testing::run_ssslab;

const char* const kSmall = testing::kSmallExperiment;

std::vector<std::string> keys(const std::string& text, bool quick = false) {
    const runner::Experiment e = runner::parse_experiment(text, "k.toml");
    runner::RunOptions o;
    o.quick = quick;
    o.results_root = "/nonexistent-results-root";
    std::vector<std::string> k;
    for (const auto& n : runner::plan(e, o).nodes) k.push_back(n.key);
    return k;
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
    const size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) s.replace(at, from.size(), to);
    return s;
}

TEST(RunnerKeys, SameConfigSameKeysAndEveryNodeDiffers) {
    const auto a = keys(kSmall), b = keys(kSmall);
    ASSERT_EQ(a.size(), 6u);
    EXPECT_EQ(a, b);
    for (size_t i = 0; i < a.size(); ++i)
        for (size_t j = i + 1; j < a.size(); ++j) EXPECT_NE(a[i], a[j]);
}

TEST(RunnerKeys, IrrelevantFormattingKeepsTheKeys) {
    const auto base = keys(kSmall);
    // Whitespace, comments, key order, number spelling, title and description.
    std::string t = kSmall;
    t = replace(t, "photons = 20000", "photons   =   2e4   # the same number");
    t = replace(t, "title = \"A small experiment\"", "title = \"Another title\"");
    t = replace(t, "description = \"Skin1 and a custom medium.\"", "description = \"\"\"x\"\"\"");
    t = replace(t, "g = 0.5\neta = 1.4", "eta = 1.40\ng = 5e-1");
    t = "# a comment\n\n" + t;
    EXPECT_EQ(keys(t), base);
    // A preset given as explicit coefficients with the same values is the same medium.
    std::string explicit_skin =
        replace(kSmall, "presets = [\"Skin1\"]\n",
                "[[materials.custom]]\nname = \"Skin1\"\nsigma_a_per_cm = [0.32, 1.7, 4.8]\n"
                "sigma_s_per_cm = [7.4, 8.8, 10.1]\neta = 1.3\n");
    const auto ek = keys(explicit_skin);
    ASSERT_EQ(ek.size(), 6u);
    // Skin1 comes after Slab here: compare as sets.
    EXPECT_EQ(std::multiset<std::string>(ek.begin(), ek.end()),
              std::multiset<std::string>(base.begin(), base.end()));
}

TEST(RunnerKeys, EveryRelevantChangeMakesNewKeys) {
    const auto base = keys(kSmall);
    const std::vector<std::pair<std::string, std::string>> changes = {
        {"seed = 7", "seed = 8"},
        {"photons = 20000", "photons = 20001"},
        {"sigma_a_per_mm = [0.1, 0.2, 0.3]", "sigma_a_per_mm = [0.1, 0.2, 0.30000000001]"},
        {"sigma_s_per_mm = [5.0, 6.0, 7.0]", "sigma_s_per_mm = [5.0, 6.0, 7.5]"},
        {"g = 0.5", "g = -0.5"},
        {"eta = 1.4", "eta = 1.41"},
        {"[outputs.profiles]", "batch_photons = 500\n[outputs.profiles]"},
        {"[outputs.profiles]", "[mcml.grid]\nnr = 100\n[outputs.profiles]"},
    };
    for (const auto& [from, to] : changes) {
        const auto k = keys(replace(kSmall, from, to));
        int changed = 0;
        for (size_t i = 0; i < k.size(); ++i) changed += k[i] != base[i];
        EXPECT_GT(changed, 0) << from << " -> " << to;
    }
    // A change to one material leaves the other's artifacts alone (only what changed reruns).
    const auto k = keys(replace(kSmall, "eta = 1.4", "eta = 1.41"));
    for (int i = 0; i < 3; ++i) EXPECT_EQ(k[static_cast<size_t>(i)], base[static_cast<size_t>(i)]);
    for (int i = 3; i < 6; ++i) EXPECT_NE(k[static_cast<size_t>(i)], base[static_cast<size_t>(i)]);
    // --quick is a different budget.
    EXPECT_NE(keys(kSmall, true), base);
}

TEST(Runner, SecondRunComputesNothingAndWritesTheSameResults) {
    testing::TempDir dir;
    dir.write("small.toml", kSmall);
    const auto dry = run_ssslab({"run", "small.toml", "--dry-run"}, dir.path());
    ASSERT_EQ(dry.exit_code, 0) << dry.err;
    EXPECT_NE(dry.out.find("6 to compute"), std::string::npos) << dry.out;
    EXPECT_FALSE(fs::exists(dir / "results")) << "--dry-run must not write";

    const auto first = run_ssslab({"run", "small.toml"}, dir.path());
    ASSERT_EQ(first.exit_code, 0) << first.err;
    EXPECT_NE(first.out.find("6 computed, 0 reused"), std::string::npos) << first.out;
    const std::string csv = testing::read_text(dir / "results" / "small" / "profiles" / "Slab.csv");
    const std::string summary = testing::read_text(dir / "results" / "small" / "summary.csv");

    const auto again = run_ssslab({"run", "small.toml", "--dry-run"}, dir.path());
    EXPECT_NE(again.out.find("6 cached, 0 to compute"), std::string::npos) << again.out;
    const auto second = run_ssslab({"run", "small.toml"}, dir.path());
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_NE(second.out.find("0 computed, 6 reused"), std::string::npos) << second.out;
    EXPECT_EQ(testing::read_text(dir / "results" / "small" / "profiles" / "Slab.csv"), csv);
    EXPECT_EQ(testing::read_text(dir / "results" / "small" / "summary.csv"), summary);
    for (const char* f : {"report.html", "metrics.csv", "artifacts.csv", "experiment.toml"})
        EXPECT_TRUE(fs::exists(dir / "results" / "small" / f)) << f;
    // Only what changed is computed again.
    dir.write("small.toml", replace(kSmall, "eta = 1.4", "eta = 1.41"));
    const auto third = run_ssslab({"run", "small.toml"}, dir.path());
    EXPECT_NE(third.out.find("3 computed, 3 reused"), std::string::npos) << third.out;
}

TEST(Runner, LayeredMaterialRunsOnBothEnginesWithItsOwnKeys) {
    // A layered custom material: MCML and the path tracer both simulate the stack, the
    // crossval table carries its transmittance, and its nodes differ from those of its top
    // layer alone (the lower layers are part of the key).
    const std::string layered = R"(
[experiment]
name = "layered"
seed = 3

[[materials.custom]]
name = "Top"
sigma_a_per_mm = [0.1, 0.2, 0.3]
sigma_s_per_mm = [5.0, 6.0, 7.0]
g = 0.5
eta = 1.4
thickness_mm = 0.5

[[materials.custom]]
name = "Stack"
[[materials.custom.layers]]
sigma_a_per_mm = [0.1, 0.2, 0.3]
sigma_s_per_mm = [5.0, 6.0, 7.0]
g = 0.5
eta = 1.4
thickness_mm = 0.5
[[materials.custom.layers]]
sigma_a_per_mm = [0.05, 0.05, 0.05]
sigma_s_per_mm = [2.0, 2.0, 2.0]
g = -0.2
eta = 1.6
thickness_mm = 1

[mcml]
photons = 5000
[volpath]
photons = 5000
[outputs.crossval]
)";
    const std::vector<std::string> k = keys(layered);
    // 2 materials x 3 channels x 2 engines; Stack differs from Top only below its top layer.
    ASSERT_EQ(k.size(), 12u);
    EXPECT_EQ(std::set<std::string>(k.begin(), k.end()).size(), 12u);
    testing::TempDir dir;
    dir.write("l.toml", layered);
    const auto r = run_ssslab({"run", "l.toml"}, dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string summary =
        testing::read_text(dir / "results" / "layered" / "crossval" / "summary.csv");
    EXPECT_NE(summary.find("\nStack,2,R,"), std::string::npos) << summary;
    EXPECT_NE(summary.find("\nTop,1,B,"), std::string::npos) << summary;
    EXPECT_EQ(summary.find("nan"), std::string::npos) << summary;
    const std::string metrics = testing::read_text(dir / "results" / "layered" / "metrics.csv");
    EXPECT_NE(metrics.find("Stack.G.volpath.Tt,"), std::string::npos);
}

TEST(Runner, BothEnginesSideBySideAreCachedCrossValidatedAndScored) {
    // [volpath] adds one path-tracer node per material and channel; crossval, pencil and
    // efficiency read both engines; a rerun computes nothing; the path tracer's nodes have keys
    // of their own (changing its budget leaves MCML's alone).
    const std::string text = std::string(kSmall) + R"(
[volpath]
photons = 20000
mode = "weighted"

[outputs.crossval]
[outputs.pencil]
models = ["dipole", "pbd"]
[outputs.efficiency]
materials = ["Skin1"]
)";
    testing::TempDir dir;
    dir.write("small.toml", text);
    const auto first = run_ssslab({"run", "small.toml"}, dir.path());
    ASSERT_EQ(first.exit_code, 0) << first.err;
    EXPECT_NE(first.out.find("13 computed, 0 reused"), std::string::npos) << first.out;
    const fs::path res = dir / "results" / "small";
    for (const char* f : {"crossval/summary.csv", "crossval/z_scores.csv", "pencil/errors.csv",
                          "pencil/Skin1.csv", "pencil/Slab.csv", "efficiency/Skin1.csv"})
        EXPECT_TRUE(fs::exists(res / f)) << f;
    const std::string summary = testing::read_text(res / "crossval" / "summary.csv");
    // Every material and channel has a chi-square over some bins and a finite z of the totals.
    std::istringstream in(summary);
    std::string line;
    std::getline(in, line);
    int rows = 0;
    while (std::getline(in, line)) {
        ++rows;
        EXPECT_EQ(line.find("nan"), std::string::npos) << line;
        EXPECT_EQ(line.find(",0,"), std::string::npos) << "no bins compared: " << line;
    }
    EXPECT_EQ(rows, 6);
    const std::string metrics = testing::read_text(res / "metrics.csv");
    for (const char* m : {"Skin1.R.volpath.Rd,", "Slab.B.volpath.Rd_single,",
                          "Skin1.G.model.pbd.Rd,", "Slab.R.model.dipole.rel_l2_rR,"})
        EXPECT_NE(metrics.find(m), std::string::npos) << m;
    const std::string errors = testing::read_text(res / "pencil" / "errors.csv");
    EXPECT_NE(errors.find("dipole,Skin1,R,volpath_multiple_scattering"), std::string::npos);
    EXPECT_NE(errors.find("pbd,Skin1,R,volpath_total"), std::string::npos);

    const auto second = run_ssslab({"run", "small.toml"}, dir.path());
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_NE(second.out.find("0 computed, 13 reused"), std::string::npos) << second.out;
    EXPECT_EQ(testing::read_text(res / "crossval" / "summary.csv"), summary);

    dir.write("small.toml", replace(text, "photons = 20000\nmode", "photons = 30000\nmode"));
    const auto third = run_ssslab({"run", "small.toml"}, dir.path());
    EXPECT_NE(third.out.find("7 computed, 6 reused"), std::string::npos) << third.out;
}

/// The column named `name` of a CSV table, as numbers.
std::vector<double> csv_column(const std::string& csv, const std::string& name) {
    const auto cells = runner::parse_csv(csv);
    const auto col = std::find(cells.at(0).begin(), cells.at(0).end(), name);
    EXPECT_NE(col, cells[0].end()) << "no column " << name;
    std::vector<double> out;
    if (col == cells[0].end()) return out;
    const size_t k = static_cast<size_t>(col - cells[0].begin());
    for (size_t row = 1; row < cells.size(); ++row) out.push_back(std::stod(cells[row].at(k)));
    return out;
}

TEST(Runner, AProfileFileIsScoredBesideTheBuiltInModelsAndKeyedByItsContent) {
    // [Issue 19] experiments/bssrdf/dipole.toml named in [outputs.pencil] by its path: its curve
    // equals the built-in dipole's (the independent C++ model) in every bin; an edit of the file
    // recomputes the model tables and nothing else; a file that is not there is refused at the
    // config's line.
    const std::string text = std::string(kSmall) + R"(
[volpath]
photons = 20000

[outputs.pencil]
models = ["dipole", "models/dipole.toml"]
)";
    testing::TempDir dir;
    dir.write("small.toml", text);
    const std::string profile =
        testing::read_text(testing::source_path("experiments/bssrdf/dipole.toml"));
    dir.write("models/dipole.toml", profile);
    const auto first = run_ssslab({"run", "small.toml"}, dir.path());
    ASSERT_EQ(first.exit_code, 0) << first.err;
    EXPECT_NE(first.out.find("13 computed, 0 reused"), std::string::npos) << first.out;
    const fs::path res = dir / "results" / "small";
    const std::string csv = testing::read_text(res / "pencil" / "Skin1.csv");
    for (const char* ch : {"R", "G", "B"}) {
        const auto builtin = csv_column(csv, std::string("dipole_") + ch + "_per_mm2");
        const auto file = csv_column(csv, std::string("dipole.toml_") + ch + "_per_mm2");
        ASSERT_EQ(builtin.size(), file.size());
        ASSERT_GT(builtin.size(), 10u);
        for (size_t k = 0; k < builtin.size(); ++k)
            EXPECT_NEAR(file[k], builtin[k], 1e-9 * std::abs(builtin[k])) << ch << " bin " << k;
    }
    const std::string metrics = testing::read_text(res / "metrics.csv");
    EXPECT_NE(metrics.find("Skin1.G.model.dipole.toml.Rd,"), std::string::npos);

    // The default multiplier 1 -> 2: the tables are computed again (only they), the curve doubles.
    dir.write("models/dipole.toml", replace(profile, "default = 1.0", "default = 2.0"));
    const auto second = run_ssslab({"run", "small.toml"}, dir.path());
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_NE(second.out.find("1 computed, 12 reused"), std::string::npos) << second.out;
    const std::string doubled = testing::read_text(res / "pencil" / "Skin1.csv");
    const auto builtin = csv_column(doubled, "dipole_R_per_mm2");
    const auto file = csv_column(doubled, "dipole.toml_R_per_mm2");
    ASSERT_EQ(builtin.size(), file.size());
    for (size_t k = 0; k < builtin.size(); ++k)
        EXPECT_NEAR(file[k], 2 * builtin[k], 1e-9 * std::abs(builtin[k])) << "bin " << k;

    // Parameters from the config, one per RGB channel (the file's default back at 1): only the
    // model tables again, the channels scaled 1, 2, 3.
    dir.write("models/dipole.toml", profile);
    const std::string with_parameters = text + R"(
[outputs.pencil.parameters."dipole.toml"]
Multiplier = [1.0, 2.0, 3.0]
)";
    dir.write("small.toml", with_parameters);
    const auto third = run_ssslab({"run", "small.toml"}, dir.path());
    ASSERT_EQ(third.exit_code, 0) << third.err;
    EXPECT_NE(third.out.find("1 computed, 12 reused"), std::string::npos) << third.out;
    const std::string scaled = testing::read_text(res / "pencil" / "Skin1.csv");
    for (int c = 0; c < 3; ++c) {
        const std::string ch = std::string(1, "RGB"[c]);
        const auto b = csv_column(scaled, "dipole_" + ch + "_per_mm2");
        const auto f = csv_column(scaled, "dipole.toml_" + ch + "_per_mm2");
        ASSERT_EQ(b.size(), f.size());
        for (size_t k = 0; k < b.size(); ++k)
            EXPECT_NEAR(f[k], (c + 1) * b[k], 1e-9 * (c + 1) * std::abs(b[k]))
                << ch << " bin " << k;
    }
    // A value outside the parameter's range, an unknown parameter, a built-in model's table:
    // refused at the config's line, exit 2.
    for (const auto& [from, to, expect] :
         std::vector<std::tuple<std::string, std::string, std::string>>{
             {"Multiplier = [1.0, 2.0, 3.0]", "Multiplier = [1.0, 20.0, 3.0]", "[0, 10]"},
             {"Multiplier = [1.0, 2.0, 3.0]", "Multiplyer = 2", "Multiplier"},
             {"parameters.\"dipole.toml\"", "parameters.dipole", "built-in"}}) {
        dir.write("small.toml", replace(with_parameters, from, to));
        const auto refused = run_ssslab({"run", "small.toml"}, dir.path());
        EXPECT_EQ(refused.exit_code, 2) << to;
        EXPECT_NE(refused.err.find("small.toml:"), std::string::npos) << refused.err;
        EXPECT_NE(refused.err.find(expect), std::string::npos) << refused.err;
    }

    dir.write("small.toml", replace(text, "models/dipole.toml", "models/dipol.toml"));
    const auto bad = run_ssslab({"run", "small.toml"}, dir.path());
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("small.toml:"), std::string::npos) << bad.err;
    EXPECT_NE(bad.err.find("no profile file"), std::string::npos) << bad.err;
    // A bad file is refused naming its own line (the reader's errors: test_expression_profile).
    dir.write("small.toml", text);
    dir.write("models/dipole.toml", replace(profile, "sigma_tr * zr", "sigma_tr * zrr"));
    const auto broken = run_ssslab({"run", "small.toml"}, dir.path());
    EXPECT_EQ(broken.exit_code, 2);
    EXPECT_NE(broken.err.find("dipole.toml:18:"), std::string::npos) << broken.err;
    EXPECT_NE(broken.err.find("zrr"), std::string::npos) << broken.err;
}

TEST(Runner, ABssrdfFileIsEvaluatedThroughGlAndScoredBesideTheBuiltInModels) {
    // [Issue 19] Listing A.2 (experiments/bssrdf/dipole.bssrdf) named in [outputs.pencil]: its
    // GLSL compiled with the config and evaluated through the GL twin's headless context; its
    // curve equals the built-in dipole's to float accuracy; GLSL that does not compile is refused
    // at the file's line with the compiler's message, exit 2, before any output.
    if (!SSSLAB_HAVE_GL) GTEST_SKIP() << "built without the GL twin";
    const std::string text = std::string(kSmall) + R"(
[volpath]
photons = 20000

[outputs.pencil]
models = ["dipole", "models/dipole.bssrdf"]
)";
    testing::TempDir dir;
    dir.write("small.toml", text);
    const std::string listing =
        testing::read_text(testing::source_path("experiments/bssrdf/dipole.bssrdf"));
    dir.write("models/dipole.bssrdf", listing);
    const auto first = run_ssslab({"run", "small.toml"}, dir.path());
    if (first.exit_code == 2 && first.err.find("no OpenGL context") != std::string::npos)
        GTEST_SKIP() << first.err;
    ASSERT_EQ(first.exit_code, 0) << first.err;
    const fs::path res = dir / "results" / "small";
    const std::string csv = testing::read_text(res / "pencil" / "Skin1.csv");
    for (const char* ch : {"R", "G", "B"}) {
        const auto builtin = csv_column(csv, std::string("dipole_") + ch + "_per_mm2");
        const auto file = csv_column(csv, std::string("dipole.bssrdf_") + ch + "_per_mm2");
        ASSERT_EQ(builtin.size(), file.size());
        ASSERT_GT(builtin.size(), 10u);
        // Float accuracy (test_bssrdf_gl): 32 u (2 + sigma_tr d) with u = 2^-24, below 2e-4 for
        // exponents up to 80; bins below float's range are left out.
        for (size_t k = 0; k < builtin.size(); ++k) {
            if (!(builtin[k] > 1e-30)) continue;
            EXPECT_NEAR(file[k], builtin[k], 2e-4 * builtin[k]) << ch << " bin " << k;
        }
    }
    EXPECT_NE(testing::read_text(res / "metrics.csv").find("Skin1.G.model.dipole.bssrdf.Rd,"),
              std::string::npos);

    // An edit of the file recomputes the model tables only.
    dir.write("models/dipole.bssrdf", replace(listing, "0.0 10.0 1.0", "0.0 10.0 2.0"));
    const auto second = run_ssslab({"run", "small.toml"}, dir.path());
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_NE(second.out.find("1 computed, 12 reused"), std::string::npos) << second.out;

    // Parameters per RGB channel from the config, as uniforms: the channels scaled 1, 2, 3.
    dir.write("models/dipole.bssrdf", listing);
    dir.write("small.toml", text + R"(
[outputs.pencil.parameters."dipole.bssrdf"]
Multiplier = [1.0, 2.0, 3.0]
)");
    const auto third = run_ssslab({"run", "small.toml"}, dir.path());
    ASSERT_EQ(third.exit_code, 0) << third.err;
    const std::string scaled = testing::read_text(res / "pencil" / "Skin1.csv");
    for (int c = 0; c < 3; ++c) {
        const std::string ch = std::string(1, "RGB"[c]);
        const auto b = csv_column(scaled, "dipole_" + ch + "_per_mm2");
        const auto f = csv_column(scaled, "dipole.bssrdf_" + ch + "_per_mm2");
        ASSERT_EQ(b.size(), f.size());
        for (size_t k = 0; k < b.size(); ++k) {
            if (!(b[k] > 1e-30)) continue;
            EXPECT_NEAR(f[k], (c + 1) * b[k], 2e-4 * (c + 1) * b[k]) << ch << " bin " << k;
        }
    }

    // Line 19 misspelled: refused with the config, at the file's line, in a fresh directory
    // that keeps no output.
    testing::TempDir bad;
    bad.write("small.toml", text);
    bad.write("models/dipole.bssrdf", replace(listing, "SigmaTPrime = SigmaSPrime + SigmaA",
                                              "SigmaTPrime = SigmaSPrme + SigmaA"));
    const auto broken = run_ssslab({"run", "small.toml"}, bad.path());
    EXPECT_EQ(broken.exit_code, 2);
    EXPECT_NE(broken.err.find("dipole.bssrdf:19:"), std::string::npos) << broken.err;
    EXPECT_NE(broken.err.find("GLSL does not compile"), std::string::npos) << broken.err;
    EXPECT_NE(broken.err.find("SigmaSPrme"), std::string::npos) << broken.err;
    EXPECT_FALSE(fs::exists(bad / "results")) << "output written for a refused config";
}

TEST(Runner, SphereTakesProfileFilesWithTheirParameters) {
    // [Issue 19] `ssslab sphere` resolves its models where the pencil study does
    // (experiments/runner/profile_models.h): a profile file named in the config, relative to it,
    // with its parameters per channel; integrated over the sphere like the built-in dipole.
    testing::TempDir dir;
    dir.write("models/dipole.toml",
              testing::read_text(testing::source_path("experiments/bssrdf/dipole.toml")));
    dir.write("sph.toml", R"(models = ["dipole", "models/dipole.toml"]
[material]
preset = "Skin1"
[parameters."dipole.toml"]
Multiplier = [1.0, 2.0, 0.5]
)");
    const auto r = run_ssslab({"sphere", "--config", "sph.toml", "--photons", "2000", "--size", "8",
                               "--threads", "2", "--out", "s", "-q"},
                              dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string csv = testing::read_text(dir / "s_beta.csv");
    const double scale[3] = {1.0, 2.0, 0.5};
    for (int c = 0; c < 3; ++c) {
        const std::string ch = std::string(1, "RGB"[c]);
        const auto b = csv_column(csv, "M_dipole_" + ch);
        const auto f = csv_column(csv, "M_dipole.toml_" + ch);
        ASSERT_EQ(b.size(), f.size());
        ASSERT_GT(b.size(), 10u);
        for (size_t k = 0; k < b.size(); ++k)
            EXPECT_NEAR(f[k], scale[c] * b[k], 1e-8 * std::abs(b[k]) + 1e-300) << ch << " " << k;
    }
    // A parameter table of a built-in model is refused at its key.
    dir.write("sph.toml", R"(models = ["dipole"]
[material]
preset = "Skin1"
[parameters.dipole]
Multiplier = 2
)");
    const auto bad = run_ssslab({"sphere", "--config", "sph.toml", "--out", "t", "-q"}, dir.path());
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("sph.toml:4:"), std::string::npos) << bad.err;
    EXPECT_NE(bad.err.find("built-in"), std::string::npos) << bad.err;
}

// Start ssslab in the background, kill it after `ms` milliseconds with `sig`, return its status.

void expect_no_partial_cache_entries(const fs::path& cache) {
    if (!fs::exists(cache)) return;
    for (const auto& kind : fs::directory_iterator(cache))
        for (const auto& e : fs::directory_iterator(kind.path())) {
            const std::string n = e.path().filename().string();
            if (e.is_directory() && n.rfind(".tmp-", 0) != 0) {
                EXPECT_TRUE(fs::exists(e.path() / "manifest.toml")) << "partial entry " << n;
            }
        }
}

TEST(Runner, KilledRunResumesToTheUninterruptedResultBitForBit) {
    const std::string big = replace(kSmall, "photons = 20000", "photons = 500000");
    testing::TempDir whole, parts;
    whole.write("big.toml", big);
    parts.write("big.toml", big);
    const auto full = run_ssslab({"run", "big.toml", "-q"}, whole.path());
    ASSERT_EQ(full.exit_code, 0) << full.err;

    // SIGKILL: no chance to save anything beyond the periodic checkpoints (every 0.1 s here).
    ::setenv("SSSLAB_CHECKPOINT_SECONDS", "0.1", 1);
    const int killed = testing::run_and_kill({"run", "big.toml", "-q"}, parts.path(), 900, SIGKILL);
    EXPECT_EQ(killed, 128 + SIGKILL) << "the run finished before it was killed";
    expect_no_partial_cache_entries(parts / "results" / "cache");
    EXPECT_FALSE(fs::exists(parts / "results" / "small" / "summary.csv"));
    // SIGINT: finishes the batches in flight, checkpoints, exits 130 without results.
    const int interrupted =
        testing::run_and_kill({"run", "big.toml", "-q"}, parts.path(), 600, SIGINT);
    ::unsetenv("SSSLAB_CHECKPOINT_SECONDS");
    if (interrupted != 0) {  // 0 if the resumed run was already done
        EXPECT_EQ(interrupted, 130);
        EXPECT_FALSE(fs::exists(parts / "results" / "small" / "summary.csv"));
    }
    expect_no_partial_cache_entries(parts / "results" / "cache");

    const auto resumed = run_ssslab({"run", "big.toml", "-q"}, parts.path());
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    for (const char* f :
         {"profiles/Skin1.csv", "profiles/Slab.csv", "summary.csv", "metrics.csv"}) {
        const std::string a = testing::read_text(whole / "results" / "small" / f);
        ASSERT_GT(a.size(), 100u) << f;
        EXPECT_EQ(a, testing::read_text(parts / "results" / "small" / f)) << f;
    }
    // The resumed run continued from the checkpoints instead of starting over.
    const std::string artifacts = testing::read_text(parts / "results" / "small" / "artifacts.csv");
    EXPECT_NE(artifacts.find(",resumed"), std::string::npos) << artifacts;
}

TEST(Runner, AnEditedConfigAfterAnInterruptNeverResumesTheOldRuns) {
    // Issue 12: interrupt, edit one material's absorption, run again: the edited material's
    // runs start afresh under their new keys (the old checkpoints are another artifact's), the
    // others resume, and the results equal an uninterrupted run of the edited config bit for bit.
    const std::string big = replace(kSmall, "photons = 20000", "photons = 500000");
    const std::string edited =
        replace(big, "sigma_a_per_mm = [0.1, 0.2, 0.3]", "sigma_a_per_mm = [0.1, 0.2, 0.45]");
    ASSERT_NE(big, edited);
    testing::TempDir whole, parts;
    whole.write("big.toml", edited);
    parts.write("big.toml", big);
    const auto full = run_ssslab({"run", "big.toml", "-q"}, whole.path());
    ASSERT_EQ(full.exit_code, 0) << full.err;
    ::setenv("SSSLAB_CHECKPOINT_SECONDS", "0.1", 1);
    const int interrupted =
        testing::run_and_kill({"run", "big.toml", "-q"}, parts.path(), 700, SIGINT);
    ::unsetenv("SSSLAB_CHECKPOINT_SECONDS");
    ASSERT_EQ(interrupted, 130) << "the run finished before the interruption";
    parts.write("big.toml", edited);
    const auto resumed = run_ssslab({"run", "big.toml"}, parts.path());
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    for (const char* f :
         {"profiles/Skin1.csv", "profiles/Slab.csv", "summary.csv", "metrics.csv"}) {
        const std::string a = testing::read_text(whole / "results" / "small" / f);
        ASSERT_GT(a.size(), 100u) << f;
        EXPECT_EQ(a, testing::read_text(parts / "results" / "small" / f)) << f;
    }
}

TEST(Runner, CheckCatchesAPlantedRegressionAndPassesAnUnchangedRerun) {
    testing::TempDir dir;
    const std::string base = replace(kSmall, "quick_factor = 0.1", "quick_factor = 0.5");
    dir.write("small.toml", base);
    const auto none = run_ssslab({"check", "small.toml", "--quick"}, dir.path());
    EXPECT_EQ(none.exit_code, 2) << none.out << none.err;
    EXPECT_NE(none.err.find("no baseline"), std::string::npos) << none.err;

    const auto update = run_ssslab({"check", "small.toml", "--quick", "--update"}, dir.path());
    ASSERT_EQ(update.exit_code, 0) << update.err;
    ASSERT_TRUE(fs::exists(dir / "results" / "baselines" / "small.quick.toml"));

    const auto same = run_ssslab({"check", "small.toml", "--quick"}, dir.path());
    EXPECT_EQ(same.exit_code, 0) << same.out << same.err;
    EXPECT_NE(same.out.find("0 regressions"), std::string::npos) << same.out;

    // Independent random streams (another seed): the same physics passes the z-tests.
    dir.write("small.toml", replace(base, "seed = 7", "seed = 99"));
    const auto reseeded = run_ssslab({"check", "small.toml", "--quick"}, dir.path());
    EXPECT_EQ(reseeded.exit_code, 0) << reseeded.out;

    // A planted regression: half as much absorption again in one channel of one material.
    dir.write("small.toml", replace(base, "sigma_a_per_mm = [0.1, 0.2, 0.3]",
                                    "sigma_a_per_mm = [0.1, 0.2, 0.45]"));
    const auto planted = run_ssslab({"check", "small.toml", "--quick"}, dir.path());
    EXPECT_EQ(planted.exit_code, 1) << planted.out;
    EXPECT_NE(planted.out.find("Slab.B."), std::string::npos) << planted.out;
    EXPECT_NE(planted.out.find("REGRESSION"), std::string::npos) << planted.out;
    EXPECT_EQ(planted.out.find("Skin1.R.Rd "), std::string::npos) << "Skin1 did not move";

    // A deterministic metric (the grid) is compared exactly.
    dir.write("small.toml",
              replace(base, "[outputs.profiles]", "[mcml.grid]\nnr = 200\n[outputs.profiles]"));
    const auto grid = run_ssslab({"check", "small.toml", "--quick"}, dir.path());
    EXPECT_EQ(grid.exit_code, 1) << grid.out;
    EXPECT_NE(grid.out.find("Skin1.nr"), std::string::npos) << grid.out;
}

struct BadConfig {
    std::string name, content;
    std::vector<std::string> expect;
};

TEST(Runner, BadExperimentConfigsAreRefusedWithTheirLocation) {
    const std::string head = "[experiment]\nname = \"x\"\n";
    const std::string mats = "[materials]\npresets = [\"Skin1\"]\n";
    const std::string outs = "[outputs.profiles]\n";
    const std::vector<BadConfig> cases = {
        {"syntax", head + "seed = = 1\n" + mats + outs, {"e.toml:3:", "TOML syntax error"}},
        {"no experiment table", mats + outs, {"key 'experiment'", "required table"}},
        {"no name",
         "[experiment]\ntitle = \"t\"\n" + mats + outs,
         {"key 'experiment.name'", "required"}},
        {"bad name",
         "[experiment]\nname = \"My Run\"\n" + mats + outs,
         {"e.toml:2:8", "experiment.name", "lower-case letters"}},
        {"unknown key", head + "sede = 1\n" + mats + outs, {"e.toml:3:1", "did you mean 'seed'"}},
        {"negative seed",
         head + "seed = -1\n" + mats + outs,
         {"e.toml:3:8", "experiment.seed", "[0, inf)"}},
        {"unknown preset",
         head + "[materials]\npresets = [\"Skim1\"]\n" + outs,
         {"e.toml:4:12", "unknown material \"Skim1\"", "did you mean \"Skin1\""}},  // the item
        {"preset twice",
         head + "[materials]\npresets = [\"Skin1\", \"skin1\"]\n" + outs,
         {"e.toml:4:21", "listed twice"}},
        {"presets not strings",
         head + "[materials]\npresets = [1, 2]\n" + outs,
         {"e.toml:4:", "materials.presets", "array of strings"}},
        {"no materials", head + "[materials]\n" + outs, {"e.toml:3:", "no materials"}},
        {"custom without name",
         head + mats + "[[materials.custom]]\nsigma_a_per_mm = 0.1\n" + outs,
         {"materials.custom[0].name", "required"}},
        {"custom bad coefficient",
         head + mats +
             "[[materials.custom]]\nname = \"c\"\nsigma_a_per_mm = -0.1\nsigma_s_per_mm = 1\neta = "
             "1.3\n" +
             outs,
         {"e.toml:7:", "materials.custom[0].sigma_a_per_mm", "[0, inf)"}},
        {"custom duplicate of preset",
         head + mats +
             "[[materials.custom]]\nname = \"Skin1\"\nsigma_a_per_mm = 0.1\nsigma_s_per_mm = "
             "1\neta = 1.3\n" +
             outs,
         {"defined twice"}},
        {"photons zero",
         head + mats + "[mcml]\nphotons = 0\n" + outs,
         {"e.toml:6:11", "mcml.photons", "[1, 9e+18]"}},
        {"quick factor above 1",
         head + mats + "[mcml]\nquick_factor = 2\n" + outs,
         {"mcml.quick_factor", "(0, 1]"}},
        {"grid both units",
         head + mats + "[mcml.grid]\ndr_mm = 0.1\ndr_cm = 0.01\n" + outs,
         {"mcml.grid.dr_cm", "not both"}},
        {"no outputs", head + mats + "[outputs]\n", {"no outputs"}},
        {"unknown output",
         head + mats + "[outputs.profils]\n",
         {"e.toml:5:", "outputs.profils", "did you mean 'profiles'"}},
        {"unknown unit",
         head + mats + "[outputs.profiles]\nunit = \"inch\"\n",
         {"outputs.profiles.unit", "\"mm\", \"cm\""}},
        {"convergence of an absent material",
         head + mats + outs + "[outputs.convergence]\nmaterials = [\"Apple\"]\n",
         {"outputs.convergence.materials", "not a material of this experiment"}},
        {"convergence reference factor",
         head + mats + outs +
             "[outputs.convergence]\nmaterials = [\"Skin1\"]\nreference_factor = 0.5\n",
         {"outputs.convergence.reference_factor", "[1, 1000]"}},
        {"convergence with a time budget",
         head + mats + "[mcml]\nseconds = 10\n" + outs +
             "[outputs.convergence]\nmaterials = [\"Skin1\"]\n",
         {"needs a photon budget"}},
        // Kernel studies ([[outputs.kernels]]).
        {"study unknown model",
         head + mats + "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"svdd:rank=1\"]\n",
         {"e.toml:7:", "outputs.kernels[0].models", "unknown model \"svdd\"", "svd:rank=N"}},
        {"study unknown model parameter",
         head + mats + "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"guided:q=1\"]\n",
         {"outputs.kernels[0].models", "unknown parameter \"q\"", "takes: b, k"}},
        {"study guided k out of range",
         head + mats + "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"guided:k=5\"]\n",
         {"outputs.kernels[0].models", "k must be in [0, 4]"}},
        {"study svd rank not a number",
         head + mats + "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"svd:rank=two\"]\n",
         {"outputs.kernels[0].models", "rank must be a number"}},
        {"study manual without unit",
         head + mats + "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"manual:table_a1\"]\n",
         {"outputs.kernels[0].models", "unit=mm or unit=cm"}},
        {"study manual fit of an unknown signal",
         head + mats + "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"manual:fit=edges\"]\n",
         {"outputs.kernels[0].models", "fit takes a test signal"}},
        {"study model twice",
         head + mats +
             "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"preintegration\", "
             "\"preintegration\"]\n",
         {"outputs.kernels[0].models", "listed twice"}},
        {"study unknown signal",
         head + mats +
             "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"preintegration\"]\nsignals = "
             "[\"egde\"]\n",
         {"e.toml:8:", "outputs.kernels[0].signals", "unknown signal \"egde\""}},
        {"study even taps",
         head + mats +
             "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"preintegration\"]\ntaps = 16\n",
         {"e.toml:8:", "outputs.kernels[0].taps", "odd number"}},
        {"study reference not a model",
         head + mats +
             "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"preintegration\"]\nsignals = "
             "[\"edge\"]\nreference = \"guided:k=1\"\n",
         {"outputs.kernels[0].reference", "not one of this study's models"}},
        {"study of an absent material",
         head + mats +
             "[[outputs.kernels]]\nname = \"k\"\nmaterials = [\"Apple\"]\nmodels = "
             "[\"preintegration\"]\n",
         {"outputs.kernels[0].materials", "not a material of this experiment"}},
        {"study unknown key",
         head + mats +
             "[[outputs.kernels]]\nname = \"k\"\nmodels = [\"preintegration\"]\nsignal = "
             "[\"edge\"]\n",
         {"e.toml:8:1", "did you mean 'signals'"}},
        // The path tracer and the outputs that compare with it.
        {"crossval without volpath",
         head + mats + "[outputs.crossval]\n",
         {"outputs.crossval", "add a [volpath] table"}},
        {"pencil without volpath",
         head + mats + "[outputs.pencil]\nmodels = [\"dipole\"]\n",
         {"outputs.pencil", "add a [volpath] table"}},
        {"unknown diffusion model",
         head + mats + "[volpath]\n[outputs.pencil]\nmodels = [\"dipol\"]\n",
         {"e.toml:7:", "outputs.pencil.models", "unknown diffusion model \"dipol\"",
          "better-dipole"}},
        {"pencil without models",
         head + mats + "[volpath]\n[outputs.pencil]\nmodels = []\n",
         {"outputs.pencil.models", "at least one"}},
        {"bad volpath mode",
         head + mats + "[volpath]\nmode = \"hero\"\n" + outs,
         {"e.toml:6:", "volpath.mode", "analog", "weighted"}},
        {"negative volpath budget",
         head + mats + "[volpath]\nphotons = -5\n" + outs,
         {"e.toml:6:", "volpath.photons"}},
        {"unknown volpath key",
         head + mats + "[volpath]\nphoton = 5\n" + outs,
         {"e.toml:6:1", "did you mean 'photons'"}},
        {"efficiency of an absent material",
         head + mats + "[volpath]\n[outputs.efficiency]\nmaterials = [\"Apple\"]\n",
         {"outputs.efficiency.materials", "not a material of this experiment"}},
        {"layered material with the diffusion models",
         head + mats +
             "[[materials.custom]]\nname = \"L\"\n[[materials.custom.layers]]\npreset = "
             "\"Apple\"\nthickness_mm = 1\n[[materials.custom.layers]]\npreset = \"Skin1\"\n"
             "[volpath]\n[outputs.pencil]\nmodels = [\"dipole\"]\n",
         {"outputs.pencil.models", "material \"L\" is layered (2 layers)"}},
        {"layered material, middle layer without thickness",
         head + mats +
             "[[materials.custom]]\nname = \"L\"\n[[materials.custom.layers]]\npreset = "
             "\"Apple\"\n[[materials.custom.layers]]\npreset = \"Skin1\"\n" +
             outs,
         {"e.toml:7:1", "materials.custom[0].layers[0].thickness_mm", "every layer but the last"}},
        {"crossval bad threshold",
         head + mats + "[volpath]\n[outputs.crossval]\nmax_rel_se = 2\n",
         {"e.toml:7:", "outputs.crossval.max_rel_se"}},
    };
    ASSERT_GE(cases.size(), 15u);
    for (const auto& c : cases) {
        SCOPED_TRACE(c.name);
        testing::TempDir dir;
        dir.write("e.toml", c.content);
        const auto r = run_ssslab({"run", "e.toml"}, dir.path());
        EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
        for (const auto& s : c.expect)
            EXPECT_NE(r.err.find(s), std::string::npos) << s << "\n" << r.err;
        EXPECT_EQ(dir.files(), std::vector<std::string>{"e.toml"}) << "no output on bad input";
    }
}

// The report of the default experiment (--quick), made once for the Report tests.
class Report : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        dir_ = new testing::TempDir;
        const auto r = run_ssslab({"run", "--quick", "-q"}, dir_->path());  // default experiment
        ok_ = r.exit_code == 0;
        err_ = r.err;
    }
    static void TearDownTestSuite() {
        delete dir_;
        dir_ = nullptr;
    }
    void SetUp() override { ASSERT_TRUE(ok_) << err_; }
    static fs::path out() { return dir_->path() / "results" / "freude14-profiles"; }
    static fs::path report() { return out() / "report.html"; }

    static bool have_chromium() { return testing::have_chromium(); }
    // testing::chromium with this suite's directory for its profile and log.
    static int chromium(const std::string& what, const fs::path& page, const std::string& size,
                        const std::string& to = "/dev/null") {
        return testing::chromium(what, page, dir_->path(), size, to);
    }

    static testing::TempDir* dir_;
    static bool ok_;
    static std::string err_;
};
testing::TempDir* Report::dir_ = nullptr;
bool Report::ok_ = false;
std::string Report::err_;

// The text of the section <h2 id="id"> up to the next <h2.
std::string section(const std::string& html, const std::string& id) {
    const size_t at = html.find("<h2 id=\"" + id + "\">");
    if (at == std::string::npos) return {};
    return html.substr(at, html.find("<h2", at + 1) - at);
}

size_t count(const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}

// The value of attribute `name` on the first element that carries it.
std::string attribute(const std::string& html, const std::string& name) {
    const size_t at = html.find(" " + name + "=\"");
    if (at == std::string::npos) return {};
    const size_t v = at + name.size() + 3;
    return html.substr(v, html.find('"', v) - v);
}

TEST_F(Report, OpensInHeadlessChromiumWithItsPlots) {
    if (!have_chromium())
        GTEST_SKIP() << "chromium is not installed (scripts/setup.sh installs it)";
    const fs::path dom = dir_->path() / "dom.html";
    ASSERT_EQ(chromium("--dump-dom", report(), "1280,2000", dom.string()), 0);
    const std::string page = testing::read_text(dom);
    EXPECT_NE(page.find("data-images-ok=\"yes\""), std::string::npos) << page.substr(0, 400);
    EXPECT_NE(page.find("data-images=\"6\""), std::string::npos);
    // The page's own console: no JavaScript errors, no failed loads.
    const std::string console = testing::read_text(dir_->path() / "chromium.log");
    EXPECT_EQ(console.find("Uncaught"), std::string::npos) << console;
    EXPECT_EQ(console.find("Failed to load resource"), std::string::npos) << console;
    // A screenshot of the rendered page.
    const fs::path shot = dir_->path() / "report.png";
    ASSERT_EQ(chromium("--screenshot='" + shot.string() + "'", report(), "1280,2000"), 0);
    ASSERT_TRUE(fs::exists(shot));
    EXPECT_GT(fs::file_size(shot), 50000u) << "a blank page compresses to a few kB";
}

TEST_F(Report, HasAContentsEntryForEverySection) {
    const std::string html = testing::read_text(report());
    const size_t nav = html.find("<nav id=\"contents\">"), nav_end = html.find("</nav>");
    ASSERT_NE(nav, std::string::npos);
    ASSERT_NE(nav_end, std::string::npos);
    EXPECT_LT(nav, html.find("<h2")) << "the contents come before the first section";
    const std::string toc = html.substr(nav, nav_end - nav);
    std::set<std::string> ids, linked;
    for (size_t at = html.find(" id=\""); at != std::string::npos; at = html.find(" id=\"", at + 1))
        ids.insert(html.substr(at + 5, html.find('"', at + 5) - at - 5));
    for (size_t at = toc.find("href=\"#"); at != std::string::npos;
         at = toc.find("href=\"#", at + 1)) {
        const std::string id = toc.substr(at + 7, toc.find('"', at + 7) - at - 7);
        EXPECT_TRUE(ids.count(id)) << "contents entry #" << id << " has no target";
        linked.insert(id);
    }
    size_t sections = 0;
    for (size_t at = html.find("<h2 id=\""); at != std::string::npos;
         at = html.find("<h2 id=\"", at + 1), ++sections) {
        const std::string id = html.substr(at + 8, html.find('"', at + 8) - at - 8);
        EXPECT_TRUE(linked.count(id)) << "section #" << id << " is not in the contents";
    }
    EXPECT_GE(sections, 6u);  // description, profiles, convergence, metrics, provenance, config
    for (const char* id : {"description", "profiles", "convergence", "metrics", "provenance"})
        EXPECT_TRUE(linked.count(id)) << id;
}

TEST_F(Report, MetricsAreTablesOfMaterialsByChannel) {
    const std::string html = testing::read_text(report());
    const std::string m = section(html, "metrics");
    ASSERT_FALSE(m.empty());
    // Every metric of metrics.csv is in the section once, as the title of its cell.
    const std::string csv = testing::read_text(out() / "metrics.csv");
    std::istringstream in(csv);
    std::string line;
    std::getline(in, line);
    size_t metrics = 0;
    while (std::getline(in, line)) {
        const std::string name = line.substr(0, line.find(','));
        EXPECT_EQ(count(m, "title=\"" + name + "\""), 1u) << name;
        ++metrics;
    }
    EXPECT_GE(metrics, 80u);
    // ... in far fewer rows than metrics: one table per quantity, a row per material.
    EXPECT_LT(count(m, "<tr>"), metrics / 2) << "not a flat list of metrics";
    // The total diffuse reflectance: a table with a column per channel and a row per material.
    const size_t rd = m.find("<caption><b>Rd</b>");
    ASSERT_NE(rd, std::string::npos) << m.substr(0, 2000);
    const std::string t = m.substr(rd, m.find("</table>", rd) - rd);
    EXPECT_NE(t.find("<th class=\"R\">R</th><th class=\"G\">G</th><th class=\"B\">B</th>"),
              std::string::npos)
        << t;
    EXPECT_EQ(count(t, "<tr>"), 6u) << "a header and five materials";
    size_t last = 0;
    for (const char* mat : {"Apple", "Marble", "Ketchup", "Skin1", "Wholemilk"}) {
        const size_t at = t.find("<tr><td class=\"l\">" + std::string(mat) + "</td>");
        ASSERT_NE(at, std::string::npos) << mat;
        EXPECT_GT(at, last) << "materials in the config's order";
        last = at;
        const size_t end = t.find("</tr>", at);
        EXPECT_EQ(count(t.substr(at, end - at), "<td"), 4u) << "material, R, G, B";
        for (const char* ch : {".R.Rd\"", ".G.Rd\"", ".B.Rd\""})
            EXPECT_NE(t.substr(at, end - at).find(std::string(mat) + ch), std::string::npos);
    }
    // The per-material grid (metrics without a channel) in one table.
    EXPECT_NE(m.find("<th title=\"rel. tol. 0\">nr [bins]</th>"), std::string::npos) << m;
}

TEST_F(Report, ProvenanceTableFitsA1280PixelWindow) {
    // The CSS that makes it fit: long values wrap, repeated ones are said once.
    const std::string html = testing::read_text(report());
    const std::string prov = section(html, "provenance");
    EXPECT_NE(prov.find("The same for every run: engine mcml"), std::string::npos) << prov;
    EXPECT_EQ(prov.find("<th class=\"l\">engine</th>"), std::string::npos);
    EXPECT_NE(html.find("table.prov td.w { white-space: normal; overflow-wrap: anywhere; }"),
              std::string::npos);
    if (!have_chromium())
        GTEST_SKIP() << "chromium is not installed (scripts/setup.sh installs it)";
    // Measured in the browser at 1280 px, on a copy of the page with a script that writes the
    // widths into the DOM (the report itself is left as it is).
    std::string copy = html;
    const std::string probe =
        "<script>window.addEventListener('load', function () {"
        "var t = document.querySelector('table.prov'), b = document.body;"
        "b.setAttribute('data-prov-right', String(Math.ceil(t.getBoundingClientRect().right)));"
        "b.setAttribute('data-prov-scroll', String(t.parentNode.scrollWidth - "
        "t.parentNode.clientWidth));"
        "b.setAttribute('data-page-width', String(document.documentElement.scrollWidth));"
        "b.setAttribute('data-page-height', String(document.documentElement.scrollHeight));"
        "});</script>";
    copy.insert(copy.rfind("</body>"), probe);
    const fs::path measure = out() / "measure.html", dom = dir_->path() / "measure-dom.html";
    std::ofstream(measure) << copy;
    ASSERT_EQ(chromium("--dump-dom", measure, "1280,2000", dom.string()), 0);
    fs::remove(measure);
    const std::string page = testing::read_text(dom);
    const std::string right = attribute(page, "data-prov-right");
    ASSERT_FALSE(right.empty()) << page.substr(0, 400);
    EXPECT_LE(std::stoi(right), 1280);
    EXPECT_EQ(attribute(page, "data-prov-scroll"), "0") << "the table's box does not scroll";
    EXPECT_LE(std::stoi(attribute(page, "data-page-width")), 1280) << "no horizontal scrolling";
    // And in a screenshot of the whole page at 1280 px: nothing is drawn in the right margin
    // (an overflowing table would run to the window's edge), and the page is not blank.
    const int height = std::stoi(attribute(page, "data-page-height"));
    ASSERT_GT(height, 2000);
    const fs::path shot = dir_->path() / "full.png";
    ASSERT_EQ(chromium("--screenshot='" + shot.string() + "'", report(),
                       "1280," + std::to_string(std::min(height, 16000))),
              0);
    const testing::RgbImage img = testing::read_png(shot);
    ASSERT_EQ(img.width, 1280);
    size_t margin = 0, ink = 0;
    int rightmost = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const unsigned char* p = img.at(x, y);
            if (p[0] > 245 && p[1] > 245 && p[2] > 245) continue;
            ++ink;
            rightmost = std::max(rightmost, x);
            if (x >= 1260) ++margin;
        }
    EXPECT_EQ(margin, 0u) << "something is drawn up to x = " << rightmost;
    EXPECT_GT(ink, static_cast<size_t>(img.width) * img.height / 50) << "a blank page";
}

TEST_F(Report, PlotsHaveNoOverlappingTextAndZoomedPanels) {
    size_t plots = 0;
    for (const auto& f : fs::directory_iterator(out() / "plots")) {
        if (f.path().extension() != ".json") continue;
        ++plots;
        const std::string j = testing::read_text(f.path());
        SCOPED_TRACE(f.path().filename().string());
        EXPECT_NE(j.find("\"overlapping_texts\": []"), std::string::npos) << j;
    }
    EXPECT_EQ(plots, 6u) << "a JSON beside every plot";
    // Ketchup's near-zero panel ends where the profile has fallen (it is a spike at r = 0 and a
    // flat line over the configured 2 MFP of its red channel, 8.3 mm).
    const std::string k = testing::read_text(out() / "plots" / "profile_Ketchup.json");
    const size_t x = k.find("\"near_zero_xlim\": [");
    ASSERT_NE(x, std::string::npos) << k;
    const double xmax = std::stod(k.substr(k.find(',', x) + 1));
    const double range = std::stod(k.substr(k.find("\"linear_range\": ") + 16));
    EXPECT_GT(range, 8.0);
    EXPECT_LT(xmax, 0.2 * range) << k;
    EXPECT_GT(xmax, 0.2) << "still shows the fall, not only the first bins";
    const std::string html = testing::read_text(report());
    EXPECT_NE(html.find("out to where every channel has fallen to 2 % of its peak"),
              std::string::npos);
    // The convergence panel: markers thinned to at most 40 per channel, one legend.
    const std::string c = testing::read_text(out() / "plots" / "convergence_Skin1.json");
    const size_t mk = c.find("\"markers_per_panel\": ");
    ASSERT_NE(mk, std::string::npos) << c;
    EXPECT_LE(std::stoi(c.substr(mk + 21)), 120);
    EXPECT_NE(c.find("\"legend_fontsize\": 10"), std::string::npos) << c;
}

// scripts/plot.py on planted inputs: the overlap check finds a planted overlap, and an
// efficiency that falls gets a caption note.
class PlotScript : public ::testing::Test {
  protected:
    void SetUp() override {
        python_ = runner::find_python();
        if (python_.empty()) GTEST_SKIP() << "no python3 with matplotlib";
    }
    int python(const std::string& code) {
        dir_.write("t.py", "import sys\nsys.path.insert(0, '" + testing::source_path("scripts") +
                               "')\nimport plot\n" + code);
        return std::system(("cd '" + dir_.path().string() + "' && MPLBACKEND=Agg '" + python_ +
                            "' t.py >out.txt 2>&1")
                               .c_str());
    }
    std::string python_;
    testing::TempDir dir_;
};

TEST_F(PlotScript, OverlapCheckFindsAPlantedOverlap) {
    ASSERT_EQ(python("import matplotlib.pyplot as plt\n"
                     "fig, ax = plt.subplots(1, 2, figsize=(4, 3))\n"  // no layout: crowded
                     "ax[1].set_ylabel('a long label ' * 4)\n"
                     "ax[0].set_xlabel('x label')\n"
                     "print('planted', plot.overlaps(fig))\n"
                     "fig, ax = plt.subplots(1, 2, figsize=(8, 3), constrained_layout=True)\n"
                     "ax[1].set_ylabel('short')\n"
                     "print('clean', plot.overlaps(fig))\n"),
              0)
        << testing::read_text(dir_ / "out.txt");
    const std::string o = testing::read_text(dir_ / "out.txt");
    EXPECT_NE(o.find("planted ['"), std::string::npos) << o;
    EXPECT_NE(o.find("axes 1 y label / axes 0 area"), std::string::npos) << o;
    EXPECT_NE(o.find("clean []"), std::string::npos) << o;
}

TEST_F(PlotScript, ATitleOverATickLabelAtTheTopIsLifted) {
    // Where the data put a log axis's limit at a labelled tick (6 x 10^5 at the top) and a long
    // title spans the tick labels, the title is moved up until nothing overlaps (found in CI:
    // the convergence figure's efficiency panel, depending on the run's wall times).
    ASSERT_EQ(python("import matplotlib.pyplot as plt\n"
                     "fig, ax = plt.subplots(1, 3, figsize=(14, 4.8), constrained_layout=True)\n"
                     "ax[2].set_yscale('log')\n"
                     "ax[2].plot([1, 2], [4e5, 6e5])\n"
                     "ax[2].set_ylim(4e5, 6e5)\n"
                     "ax[2].set_title('efficiency 1 / (rel. variance x time), 16 batches on and "
                     "more', pad=0)\n"
                     "plot.declutter(fig)\n"
                     "print('planted', plot.overlaps(fig))\n"
                     "plot.lift_titles(fig)\n"
                     "print('lifted', plot.overlaps(fig))\n"),
              0)
        << testing::read_text(dir_ / "out.txt");
    const std::string o = testing::read_text(dir_ / "out.txt");
    EXPECT_NE(o.find("planted ['axes 2 title / axes 2 y tick"), std::string::npos) << o;
    EXPECT_NE(o.find("lifted []"), std::string::npos) << o;
}

TEST_F(PlotScript, AFallingEfficiencyGetsACaption) {
    // Efficiency = 1 / (rel_se^2 t): flat when rel_se falls as 1/sqrt(t); falling when it falls
    // as t^-1/4 at a steady throughput (the variance per photon rose), or when the batches take
    // longer and longer (the throughput fell).
    std::ostringstream flat, falling, slower, snaps;
    const std::string head =
        "channel,batches,photons,seconds,Rd,Rd_se,Rd_reference,Rd_reference_se,abs_error,"
        "rel_error,rel_se,efficiency_per_s\n";
    flat << head;
    falling << head;
    slower << head;
    for (const char* c : {"R", "G", "B"})
        for (int b = 2; b <= 256; ++b) {
            const double t = 0.01 * b, photons = 1000.0 * b;
            const double se_flat = 0.1 / std::sqrt(b), se_fall = 0.1 / std::pow(b, 0.25);
            auto row = [&](std::ostringstream& os, double rse, double sec) {
                os << c << ',' << b << ',' << photons << ',' << sec << ",0.5," << 0.5 * rse
                   << ",0.5,0.0001,0.001,0.002," << rse << ',' << 1 / (rse * rse * sec) << '\n';
            };
            row(flat, se_flat, t);
            row(falling, se_fall, t);
            row(slower, se_flat, 0.0001 * b * b);
        }
    snaps << "channel,batches,photons,seconds,rRd_rel_l2_error,rRd_rel_l2_reference_floor\n"
          << "R,4,4000,0.04,0.1,0.01\nR,8,8000,0.08,0.07,0.01\n";
    dir_.write("flat.csv", flat.str());
    dir_.write("falling.csv", falling.str());
    dir_.write("slower.csv", slower.str());
    dir_.write("snaps.csv", snaps.str());
    ASSERT_EQ(python("for h in ('flat', 'falling', 'slower'):\n"
                     "    plot.convergence_plot('.', {'history': h + '.csv', 'snapshots': "
                     "'snaps.csv', 'title': h, 'out': h})\n"),
              0)
        << testing::read_text(dir_ / "out.txt");
    const std::string fl = testing::read_text(dir_ / "flat.json");
    const std::string fa = testing::read_text(dir_ / "falling.json");
    EXPECT_NE(fl.find("\"notes\": []"), std::string::npos) << fl;
    for (const char* ch : {"channel R", "channel G", "channel B"})
        EXPECT_NE(fa.find("The efficiency of " + std::string(ch) + " falls"), std::string::npos)
            << fa;
    EXPECT_NE(fa.find("The throughput held"), std::string::npos) << fa;
    const std::string sl = testing::read_text(dir_ / "slower.json");
    EXPECT_NE(sl.find("The efficiency of channel R falls"), std::string::npos) << sl;
    EXPECT_NE(sl.find("The throughput fell with it"), std::string::npos) << sl;
    EXPECT_NE(fa.find("\"overlapping_texts\": []"), std::string::npos) << fa;
}

// The notes of a plot's JSON reach its caption in report.html, also for a plot from the cache.
TEST(ReportPlots, CaptionsCarryThePlotNotes) {
    if (runner::find_python().empty()) GTEST_SKIP() << "no python3 with matplotlib";
    testing::TempDir dir;
    dir.write("s.toml", std::string(kSmall) + "\n[outputs.profile_plots]\n");
    ASSERT_EQ(run_ssslab({"run", "s.toml", "--quick", "-q"}, dir.path()).exit_code, 0);
    size_t planted = 0;
    for (const auto& f : fs::recursive_directory_iterator(dir / "results" / "cache" / "plot"))
        if (f.path().filename() == "plot.json") {
            std::string j = testing::read_text(f.path());
            const size_t at = j.find("\"notes\": [");
            ASSERT_NE(at, std::string::npos) << j;
            j.insert(at + 10, "\"A planted \\\"note\\\" for the caption.\"");
            std::ofstream(f.path()) << j;
            ++planted;
        }
    EXPECT_EQ(planted, 2u) << "one plot per material";
    ASSERT_EQ(run_ssslab({"run", "s.toml", "--quick", "-q"}, dir.path()).exit_code, 0);
    const std::string html = testing::read_text(dir / "results" / "small" / "report.html");
    EXPECT_EQ(
        count(html, "Bands: +-2 standard errors. A planted &quot;note&quot; for the caption."), 2u)
        << html;
}

// [outputs.render]: scenes rendered through the artifact graph (cached EXRs, reuse, rays/s and
// time to 1 % in the summary, metrics for `ssslab check`), and its config errors.
const char* kRenderScene = R"(
[scene]
name = "tiny"
[camera]
position = [0, 0, 40]
target = [0, 0, 0]
fov_y_deg = 30
width = 256
height = 256
[[lights]]
type = "environment"
radiance = [1, 1, 1]
[[materials]]
name = "m"
preset = "Skin1"
roughness = 0.3
[[shapes]]
type = "sphere"
radius = 8
subdivisions = 3
material = "m"
)";

const char* kRenderExp = R"(
[experiment]
name = "renders"
seed = 3
[outputs.render]
scenes = ["scenes/tiny.toml"]
spp = 24
width = 24
height = 16
reference_factor = 2
)";

TEST(RunnerRender, ScenesAreRenderedCachedAndReportedWithTheirSpeed) {
    testing::TempDir dir;
    dir.write("scenes/tiny.toml", kRenderScene);
    dir.write("r.toml", kRenderExp);
    const auto first = run_ssslab({"run", "r.toml"}, dir.path());
    ASSERT_EQ(first.exit_code, 0) << first.err << first.out;
    EXPECT_NE(first.out.find("2 computed, 0 reused"), std::string::npos) << first.out;
    const fs::path out = dir / "results" / "renders" / "render";
    for (const char* f : {"tiny.exr", "tiny.png", "summary.csv", "tiny_convergence.csv"})
        EXPECT_TRUE(fs::exists(out / f)) << f;
    const LayeredImage im = read_exr((out / "tiny.exr").string());
    EXPECT_EQ(im.width(), 24);
    EXPECT_EQ(im.height(), 16);
    EXPECT_TRUE(im.has_layer("radiance.stderr"));
    EXPECT_FALSE(im.has_layer("snapshot_4")) << "snapshots stay in the cache";
    const std::string summary = testing::read_text(out / "summary.csv");
    std::istringstream is(summary);
    std::string header, row;
    std::getline(is, header);
    std::getline(is, row);
    EXPECT_EQ(header.rfind("scene,width,height,spp,seconds,threads,rays,mrays_per_s", 0), 0u);
    EXPECT_EQ(row.rfind("tiny,24,16,24,", 0), 0u) << row;
    // The convergence table: the snapshot after 4 batches (of 3 spp) and the final 24 spp.
    const std::string conv = testing::read_text(out / "tiny_convergence.csv");
    EXPECT_NE(conv.find("\n12,"), std::string::npos) << conv;
    EXPECT_NE(conv.find("\n24,"), std::string::npos) << conv;
    // The final image against the reference (volpath::measured_error): the image RMS, the one
    // the convergence table ends with, and the measured median pixel with its time to 1 %.
    auto cells = [](const std::string& line) {
        std::vector<std::string> c;
        std::istringstream in(line);
        for (std::string x; std::getline(in, x, ',');) c.push_back(x);
        return c;
    };
    const auto h = cells(header), v = cells(row);
    ASSERT_EQ(h.size(), v.size()) << header << "\n" << row;
    auto at = [&](const char* name) {
        const auto i = std::find(h.begin(), h.end(), name);
        EXPECT_NE(i, h.end()) << name;
        return i == h.end() ? std::string() : v[static_cast<size_t>(i - h.begin())];
    };
    const std::string last = conv.substr(conv.find("\n24,") + 1);
    EXPECT_EQ(cells(last.substr(0, last.find('\n')))[2], at("rel_rmse_vs_reference")) << conv;
    EXPECT_GT(std::stod(at("median_pixel_measured")), 0);
    EXPECT_GT(std::stod(at("z2_median_ratio")), 0);
    EXPECT_GT(std::stod(at("t_1pct_median_pixel_from_reference_s")), 0);
    const std::string metrics = testing::read_text(dir / "results" / "renders" / "metrics.csv");
    EXPECT_NE(metrics.find("tiny.G.radiance_mean"), std::string::npos) << metrics;
    EXPECT_NE(metrics.find("tiny.B.subsurface_mean"), std::string::npos) << metrics;
    EXPECT_NE(
        testing::read_text(dir / "results" / "renders" / "report.html").find("render/tiny.png"),
        std::string::npos);

    // Again: nothing rendered, the same image.
    const auto second = run_ssslab({"run", "r.toml"}, dir.path());
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_NE(second.out.find("0 computed, 2 reused"), std::string::npos) << second.out;
    const LayeredImage again = read_exr((out / "tiny.exr").string());
    const auto a = im.layer("radiance").pixels(), b = again.layer("radiance").pixels();
    EXPECT_TRUE(std::equal(a.begin(), a.end(), b.begin(), b.end()));
    // The baseline check of an unchanged rerun passes.
    const auto upd = run_ssslab({"check", "r.toml", "--update"}, dir.path());
    ASSERT_EQ(upd.exit_code, 0) << upd.err << upd.out;
    const auto chk = run_ssslab({"check", "r.toml"}, dir.path());
    EXPECT_EQ(chk.exit_code, 0) << chk.err << chk.out;

    // A change to the scene file renders both again; a change of the reference factor only the
    // reference.
    dir.write("scenes/tiny.toml", replace(kRenderScene, "roughness = 0.3", "roughness = 0.31"));
    const auto third = run_ssslab({"run", "r.toml"}, dir.path());
    EXPECT_NE(third.out.find("2 computed, 0 reused"), std::string::npos) << third.out;
    dir.write("r.toml", replace(kRenderExp, "reference_factor = 2", "reference_factor = 3"));
    const auto fourth = run_ssslab({"run", "r.toml"}, dir.path());
    EXPECT_NE(fourth.out.find("1 computed, 1 reused"), std::string::npos) << fourth.out;
}

TEST(RunnerRender, BadRenderConfigsAreRefusedWithTheirLocation) {
    testing::TempDir dir;
    dir.write("scenes/tiny.toml", kRenderScene);
    dir.write("scenes/bad.toml", replace(kRenderScene, "radius = 8", "radius = -8"));
    const std::vector<BadConfig> cases = {
        {"no budget", replace(kRenderExp, "spp = 24\n", ""), {"e.toml:", "spp", "give a budget"}},
        {"missing scene",
         replace(kRenderExp, "scenes/tiny.toml", "scenes/none.toml"),
         {"e.toml:6:", "no scene file"}},
        {"bad scene",
         replace(kRenderExp, "scenes/tiny.toml", "scenes/bad.toml"),
         {"bad.toml:", "radius"}},
        {"width without height", replace(kRenderExp, "height = 16\n", ""), {"e.toml:", "width"}},
        {"materials nobody reads",
         std::string(kRenderExp) + "[materials]\npresets = [\"Skin1\"]\n",
         {"e.toml:", "no output of this experiment reads materials"}},
        {"both budgets",
         replace(kRenderExp, "spp = 24", "spp = 24\nseconds = 2"),
         {"e.toml:", "not both"}},
    };
    for (const auto& c : cases) {
        dir.write("e.toml", c.content);
        const auto r = run_ssslab({"run", "e.toml"}, dir.path());
        EXPECT_EQ(r.exit_code, 2) << c.name << "\n" << r.err;
        for (const auto& piece : c.expect)
            EXPECT_NE(r.err.find(piece), std::string::npos) << c.name << ": " << piece << "\n"
                                                            << r.err;
        EXPECT_FALSE(fs::exists(dir / "results" / "renders")) << c.name;
    }
}

}  // namespace
}  // namespace ssslab
