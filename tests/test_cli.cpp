// The `ssslab` command line end to end: help, outputs and their provenance, determinism across
// thread counts, and an interrupted run that resumes to the result of an uninterrupted one.
#include "core/build_info.h"
#include "core/profile.h"
#include "testing.h"

#include <gtest/gtest.h>
#include <toml++/toml.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab {
namespace {

namespace fs = std::filesystem;
using testing::data_path;
using testing::run_ssslab;

TEST(Cli, HelpForEveryCommand) {
    testing::TempDir dir;
    for (const char* cmd : {"run", "check", "mcml", "profile", "sphere", "materials", "scene",
                            "render", "raster", "bench"}) {
        const auto r = run_ssslab({cmd, "--help"}, dir.path());
        EXPECT_EQ(r.exit_code, 0) << cmd << ": " << r.err;
        EXPECT_NE(r.out.find("--help"), std::string::npos) << cmd;
    }
    const auto top = run_ssslab({"--help"}, dir.path());
    EXPECT_EQ(top.exit_code, 0);
    for (const char* cmd : {"run", "check", "mcml", "profile", "sphere", "materials", "scene",
                            "render", "raster", "bench"})
        EXPECT_NE(top.out.find(cmd), std::string::npos) << cmd;
    const auto version = run_ssslab({"--version"}, dir.path());
    EXPECT_EQ(version.exit_code, 0);
    EXPECT_NE(version.out.find("oneTBB"), std::string::npos) << version.out;
    EXPECT_TRUE(dir.files().empty());
}

// The help text of a command's option, from its name to the next option.
std::string option_help(const std::string& help, const std::string& option) {
    const size_t at = help.find("  " + option + " ");
    if (at == std::string::npos) return {};
    const size_t next = help.find("\n  -", at + 1);
    return help.substr(at, next == std::string::npos ? std::string::npos : next - at);
}

TEST(Cli, EachCommandListsOnlyItsOwnOptionsDescribedForIt) {
    testing::TempDir dir;
    const auto render = run_ssslab({"render", "--help"}, dir.path());
    ASSERT_EQ(render.exit_code, 0) << render.err;
    const std::string& h = render.out;
    for (const char* opt : {"--spp", "--time", "--rel-error", "--seed", "--threads", "--out",
                            "--quiet", "--width", "--reference"})
        EXPECT_NE(h.find(opt), std::string::npos) << opt << " in\n" << h;
    // render counts samples per pixel (--spp); photons and batches are other commands' budgets.
    EXPECT_EQ(h.find("--photons"), std::string::npos) << h;
    EXPECT_EQ(h.find("--batch "), std::string::npos) << h;
    // Its batch size is in samples per pixel too.
    EXPECT_NE(option_help(h, "--batch-spp").find("Samples per pixel in a batch"), std::string::npos)
        << h;
    EXPECT_EQ(h.find("diffuse reflectance"), std::string::npos) << h;
    // Its relative error is a pixel's (the median lit pixel), the image mean's on request.
    EXPECT_NE(option_help(h, "--rel-error").find("median pixel"), std::string::npos) << h;
    EXPECT_NE(option_help(h, "--rel-error-of").find("image-mean"), std::string::npos) << h;
    EXPECT_NE(option_help(h, "--fresh").find("checkpoint"), std::string::npos) << h;
    EXPECT_NE(option_help(h, "--spp").find("samples per pixel"), std::string::npos) << h;
    // No 300-digit bound of a double in any check's description.
    EXPECT_EQ(h.find("17976931348623157"), std::string::npos) << h;

    for (const char* cmd : {"mcml", "profile"}) {
        const auto r = run_ssslab({cmd, "--help"}, dir.path());
        ASSERT_EQ(r.exit_code, 0) << r.err;
        for (const char* opt : {"--photons", "--time", "--rel-error", "--batch", "--seed"})
            EXPECT_NE(r.out.find(opt), std::string::npos) << cmd << " " << opt;
        EXPECT_NE(option_help(r.out, "--rel-error").find("total diffuse"), std::string::npos)
            << cmd << ":\n"
            << r.out;
    }
    const auto mcml = run_ssslab({"mcml", "--help"}, dir.path());
    EXPECT_NE(option_help(mcml.out, "--photons").find(".mci"), std::string::npos) << mcml.out;
    const auto profile = run_ssslab({"profile", "--help"}, dir.path());
    EXPECT_NE(option_help(profile.out, "--unit").find("mm (default"), std::string::npos)
        << profile.out;
    const auto sphere = run_ssslab({"sphere", "--help"}, dir.path());
    EXPECT_NE(option_help(sphere.out, "--rel-error").find("exitance"), std::string::npos)
        << sphere.out;
    EXPECT_TRUE(dir.files().empty());
}

// Command-line values: exit 2 and one short readable line (see test_bad_input for the table).
TEST(Cli, BadValuesExitTwoWithAShortMessage) {
    testing::TempDir dir;
    dir.write("s.toml", "# not read\n");
    const auto r = run_ssslab({"render", "s.toml", "--spp", "0"}, dir.path());
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("ssslab render: error: --spp: must be a positive integer, got 0"),
              std::string::npos)
        << r.err;
    EXPECT_LT(r.err.size(), 200u) << r.err;
    EXPECT_EQ(r.out, "");
    const auto missing = run_ssslab({"render", "x.toml"}, dir.path());
    EXPECT_EQ(missing.exit_code, 2);
    EXPECT_EQ(missing.err.rfind("ssslab render: error: scene file 'x.toml' does not exist\n", 0),
              0u)
        << missing.err;
    EXPECT_EQ(dir.files(), std::vector<std::string>{"s.toml"});
}

// The CSV is in mm unless asked for cm, as the experiments and reports are.
TEST(Cli, ProfileUnitIsMmByDefault) {
    testing::TempDir dir;
    for (const std::string unit : {"", "cm"}) {
        std::vector<std::string> args = {
            "profile", "-m", "Skin1", "--photons", "300", "--out", "p" + unit + ".csv"};
        if (!unit.empty()) args.insert(args.end(), {"--unit", unit});
        const auto r = run_ssslab(args, dir.path());
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const std::string csv = testing::read_text(dir / ("p" + unit + ".csv"));
        const std::string rec = testing::read_text(dir / ("p" + unit + ".csv.toml"));
        const std::string want = unit.empty() ? "mm" : "cm";
        EXPECT_NE(csv.find("r_mid_" + want), std::string::npos) << csv.substr(0, 300);
        EXPECT_NE(csv.find("Rd_R_per_" + want + "2"), std::string::npos) << csv.substr(0, 300);
        EXPECT_NE(rec.find("unit = '" + want + "'"), std::string::npos) << rec;
        EXPECT_NE(r.out.find(" " + want + " (Skin1)"), std::string::npos) << r.out;
    }
}

TEST(Cli, MaterialsListsTheElevenPresets) {
    testing::TempDir dir;
    const auto r = run_ssslab({"materials"}, dir.path());
    ASSERT_EQ(r.exit_code, 0);
    for (const char* m : {"Apple", "Chicken1", "Chicken2", "Cream", "Ketchup", "Marble", "Potato",
                          "Skimmilk", "Skin1", "Skin2", "Wholemilk"})
        EXPECT_NE(r.out.find(m), std::string::npos) << m;
}

TEST(Cli, ProfileWritesCsvWithResolvedConfigurationBesideIt) {
    testing::TempDir dir;
    const auto r = run_ssslab(
        {"profile", "--material", "Skin1", "--photons", "3000", "--unit", "mm", "--out", "p.csv"},
        dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(dir.files(), (std::vector<std::string>{"p.csv", "p.csv.toml"}));
    const RadialProfile p = read_profile_csv((dir / "p.csv").string());
    EXPECT_EQ(p.nr, 1236);  // Freude14 Table 6.1 for Skin1
    for (int c = 0; c < 3; ++c) {
        EXPECT_GT(p.rd_per_cm2[c][0], 0.0);
        EXPECT_GT(p.se_per_cm2[c][0], 0.0);
    }
    const std::string rec = testing::read_text(dir / "p.csv.toml");
    for (const char* key : {"preset = 'Skin1'", "seed = 1", "photons = 3000",
                            "rule = ", "[result_R]", "Rd_se", "stop_reason = 'photons'",
                            "[provenance]", "git_revision", "command_line", "[simulated_medium]",
                            "eta = [ 1.3 ]", "eta_above = 1.0", "eta_below = 1.0", "boundary = "})
        EXPECT_NE(rec.find(key), std::string::npos) << key << " in\n" << rec;
    // The medium as simulated, not only the preset's name: Skin1 of Freude14 Table 6.2 (sigma_a
    // 0.032, 0.17, 0.48 and sigma_s 0.74, 0.88, 1.01 per mm, g 0, eta 1.3).
    const toml::table t = toml::parse(rec);
    const double sa[3] = {0.32, 1.7, 4.8}, ss[3] = {7.4, 8.8, 10.1};
    for (int c = 0; c < 3; ++c) {
        EXPECT_DOUBLE_EQ(t["simulated_medium"]["sigma_a_per_cm"][0][c].value_or(-1.0), sa[c]);
        EXPECT_DOUBLE_EQ(t["simulated_medium"]["sigma_s_per_cm"][0][c].value_or(-1.0), ss[c]);
        EXPECT_EQ(t["simulated_medium"]["g"][0][c].value_or(-1.0), 0.0);
    }
}

// The GL twin's rows (realtime/gl): the SSS pass's draws and its whole call, per scene, and its
// result against the CPU pass's on the frame's own inputs.
TEST(Cli, BenchRealtimeWithTheGlTwin) {
    if (!SSSLAB_HAVE_GL) GTEST_SKIP() << "built without the GL twin";
    testing::TempDir dir;
    const std::string scenes = testing::source_path("experiments/scenes");
    const auto r = run_ssslab({"bench", "--realtime", "--quick", "--threads", "2", "--scenes",
                               scenes, "--case", "ketchup", "--backend", "gl", "--csv", "b.csv"},
                              dir.path());
    if (r.exit_code != 0 && r.err.find("no OpenGL context") != std::string::npos)
        GTEST_SKIP() << r.err;
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // Both frames (the scene and its one-light variant): the GL pass equals the CPU pass to
    // 1e-5 relative on the frame's inputs.
    size_t at = 0, compared = 0;
    const std::string key = "worst relative difference ";
    while ((at = r.out.find(key, at)) != std::string::npos) {
        at += key.size();
        EXPECT_LT(std::stod(r.out.substr(at)), 1e-5) << r.out;
        ++compared;
    }
    EXPECT_EQ(compared, 2u) << r.out;
    const std::string csv = testing::read_text(dir / "b.csv");
    for (const char* row : {"ketchup,480,270,gl,0,sss,", "ketchup,480,270,gl,0,sss+transfer,",
                            "ketchup/1-light,480,270,gl,0,sss,"})
        EXPECT_NE(csv.find(row), std::string::npos) << row << "\n" << csv;
}

// --integrations: Munoz11 and Jensen-Buhler timed in place of the SSS pass, the scene with its
// lights only, at all threads; refused without --realtime.
TEST(Cli, BenchRealtimeTimesTheSurfaceIntegrations) {
    testing::TempDir dir;
    const std::string scenes = testing::source_path("experiments/scenes");
    auto r =
        run_ssslab({"bench", "--realtime", "--quick", "--threads", "2", "--scenes", scenes,
                    "--case", "ketchup", "--size", "96x72", "--integrations", "--csv", "b.csv"},
                   dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string csv = testing::read_text(dir / "b.csv");
    for (const char* row :
         {"ketchup,96,72,software,2,munoz l4,", "ketchup,96,72,software,2,munoz l4 t.001 d2,",
          "ketchup,96,72,software,2,jb d4 cloud,", "ketchup,96,72,software,2,jb d4 t.03 queries,"})
        EXPECT_NE(csv.find(row), std::string::npos) << row << "\n" << csv;
    EXPECT_EQ(csv.find("ketchup/1-light,96,72,software,2,munoz"), std::string::npos) << csv;
    EXPECT_NE(r.out.find("points in the cloud"), std::string::npos) << r.out;
    r = run_ssslab({"bench", "--integrations"}, dir.path());
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--realtime"), std::string::npos) << r.err;
}

TEST(Cli, BenchRealtimeWritesPassTimesPerSceneAndThreadCount) {
    testing::TempDir dir;
    const std::string scenes = testing::source_path("experiments/scenes");
    const auto r = run_ssslab(
        {"bench", "--realtime", "--quick", "--threads", "2", "--scenes", scenes, "--csv", "b.csv"},
        dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("floor_ms"), std::string::npos) << r.out;
    // Besides the table, only the MCML profiles of the scenes' media, in the artifact cache.
    std::vector<std::string> files;
    for (const std::string& f : dir.files())
        if (f.rfind("results/cache/mcml-channel/", 0) != 0) files.push_back(f);
    EXPECT_EQ(files, (std::vector<std::string>{"b.csv", "b.csv.toml"}));
    EXPECT_NE(testing::read_text(dir / "b.csv.toml").find("[provenance]"), std::string::npos);
    std::istringstream csv(testing::read_text(dir / "b.csv"));
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line, "scene,width,height,backend,threads,pass,ms,floor_ms");
    std::set<std::string> seen;
    while (std::getline(csv, line)) {
        std::vector<std::string> f;
        std::istringstream in(line);
        for (std::string x; std::getline(in, x, ',');) f.push_back(x);
        if (line.back() == ',') f.push_back("");
        ASSERT_EQ(f.size(), 8u) << line;
        EXPECT_EQ(f[1], "480");
        EXPECT_EQ(f[2], "270");
        EXPECT_EQ(f[3], "software");
        EXPECT_GT(std::stod(f[6]), 0.0) << line;
        if (f[5] == "sss") {
            ASSERT_FALSE(f[7].empty()) << line;
            EXPECT_GT(std::stod(f[7]), 0.0) << line;
        } else {
            EXPECT_TRUE(f[7].empty()) << line;
        }
        seen.insert(f[0] + "/" + f[4] + "/" + f[5]);
    }
    for (const char* scene : {"apple", "ketchup", "marble", "skin", "wholemilk"})
        for (const char* threads : {"1", "2"})
            for (const char* pass :
                 {"raster", "shadow maps", "lighting", "sss", "composite", "frame"})
                EXPECT_TRUE(seen.count(std::string(scene) + "/" + threads + "/" + pass))
                    << scene << " " << threads << " " << pass;

    for (const std::vector<std::string>& bad :
         {std::vector<std::string>{"bench", "--realtime", "--size", "0x10"},
          {"bench", "--realtime", "--size", "64x"},
          {"bench", "--size", "64"},
          {"bench", "--realtime", "--backend", "vulkan"},
          {"bench", "--realtime", "--backend", "gl", "--platform", "glx"},
          {"bench", "--render", "--backend", "gl"}}) {
        const auto b = run_ssslab(bad, dir.path());
        EXPECT_EQ(b.exit_code, 2) << bad.back() << ": " << b.err;
    }
}

// `bench --original PATH` runs a program on the bench's own .mci (here a stand-in that only
// writes the output file the .mci names) and divides by its time; a program that fails or
// writes nothing is refused, exit 2, naming it.
TEST(Cli, BenchTimesTheOriginalProgramOnTheSameInputs) {
    testing::TempDir dir;
    const auto script = [&](const std::string& name, const std::string& body) {
        const fs::path p = dir.write(name, "#!/bin/sh\n" + body);
        fs::permissions(p, fs::perms::owner_all);
        return p.string();
    };
    // The output name is the first word of the first line that names a .mco.
    const std::string fake =
        script("fake_mcml", "sleep 0.05; touch \"$(grep -m1 -o '^[^ \t]*\\.mco' \"$1\")\"\n");
    const auto r = run_ssslab({"bench", "--case", "Skin1 red, full", "--quick", "--repeat", "1",
                               "--threads", "1", "--original", fake},
                              dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("timed in this run on the same inputs"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("Skin1 red, full tallies"), std::string::npos) << r.out;
    for (const std::string& body : {std::string("exit 1\n"), std::string("exit 0\n")}) {
        const std::string bad = script("bad_mcml", body);
        const auto b = run_ssslab(
            {"bench", "--case", "Skin1 red, full", "--quick", "--repeat", "1", "--original", bad},
            dir.path());
        EXPECT_EQ(b.exit_code, 2) << body << b.err;
        EXPECT_NE(b.err.find("bad_mcml"), std::string::npos) << b.err;
    }
    const auto missing =
        run_ssslab({"bench", "--original", (dir / "nonesuch").string()}, dir.path());
    EXPECT_EQ(missing.exit_code, 2) << missing.err;
}

TEST(Cli, McmlDefaultModeIsIndependentOfThreads) {
    testing::TempDir one, two;
    for (auto* d : {&one, &two}) fs::copy_file(data_path("mcml-1.2.2/a_vdh.mci"), *d / "a.mci");
    const auto r1 =
        run_ssslab({"mcml", "a.mci", "--photons", "50000", "--threads", "1"}, one.path());
    const auto r2 =
        run_ssslab({"mcml", "a.mci", "--photons", "50000", "--threads", "2"}, two.path());
    ASSERT_EQ(r1.exit_code, 0) << r1.err;
    ASSERT_EQ(r2.exit_code, 0) << r2.err;
    for (const char* f : {"a_vdh.mco", "a_vdh_stderr.mco"})
        EXPECT_EQ(testing::lines_from(testing::read_text(one / f), 11),
                  testing::lines_from(testing::read_text(two / f), 11))
            << f;
    EXPECT_NE(r1.out.find("Rd 0.09"), std::string::npos) << r1.out;
}

TEST(Cli, InterruptedRunResumesToTheUninterruptedResult) {
    testing::TempDir whole, parts;
    for (auto* d : {&whole, &parts})
        fs::copy_file(data_path("mcml-1.2.2/b_giov_n15.mci"), *d / "b.mci");
    const std::vector<std::string> args = {"mcml",      "b.mci", "--photons", "4000000",
                                           "--threads", "2",     "--batch",   "20000"};
    const auto full = run_ssslab(args, whole.path());
    ASSERT_EQ(full.exit_code, 0) << full.err;

    // Start the same run, interrupt it with SIGINT, and check it saved a checkpoint only.
    std::vector<std::string> quiet = args;
    quiet.push_back("-q");
    ASSERT_EQ(testing::run_and_kill(quiet, parts.path(), 700, SIGINT), 130)
        << "the run finished before the interruption";
    EXPECT_EQ(parts.files(), (std::vector<std::string>{"b.mci", "b_giov_n15.mco.ckpt"}));

    const auto resumed = run_ssslab(args, parts.path());
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    for (const char* f : {"b_giov_n15.mco", "b_giov_n15_stderr.mco"})
        EXPECT_EQ(testing::lines_from(testing::read_text(whole / f), 11),
                  testing::lines_from(testing::read_text(parts / f), 11))
            << f;
    EXPECT_NE(
        testing::read_text(parts / "b_giov_n15.mco.toml").find("resumed_from_checkpoint = 'yes'"),
        std::string::npos);
    EXPECT_FALSE(fs::exists(parts / "b_giov_n15.mco.ckpt"));
}

TEST(Cli, ABadCheckpointIntervalInTheEnvironmentIsRefusedByName) {
    testing::TempDir dir;
    fs::copy_file(data_path("mcml-1.2.2/b_giov_n15.mci"), dir / "b.mci");
    ::setenv("SSSLAB_CHECKPOINT_SECONDS", "soon", 1);
    const auto r = run_ssslab({"mcml", "b.mci", "--photons", "1000"}, dir.path());
    ::unsetenv("SSSLAB_CHECKPOINT_SECONDS");
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("SSSLAB_CHECKPOINT_SECONDS"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("'soon'"), std::string::npos) << r.err;
    EXPECT_EQ(dir.files(), std::vector<std::string>{"b.mci"});
}

TEST(Cli, RunWithoutArgumentsIsTheDefaultExperiment) {
    testing::TempDir dir;
    const auto dry = run_ssslab({"--dry-run"}, dir.path());  // no command: `run`
    EXPECT_EQ(dry.exit_code, 0) << dry.err;
    EXPECT_NE(dry.out.find("experiment freude14-profiles: 18 artifacts"), std::string::npos)
        << dry.out;
    const auto r = run_ssslab({"run", "--quick", "-q", "--results", "d"}, dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (const char* m : {"Apple", "Marble", "Ketchup", "Skin1", "Wholemilk"})
        EXPECT_TRUE(
            fs::exists(dir / "d" / "freude14-profiles" / "profiles" / (std::string(m) + ".csv")))
            << m;
    EXPECT_TRUE(fs::exists(dir / "d" / "freude14-profiles" / "report.html"));
}

}  // namespace
}  // namespace ssslab
