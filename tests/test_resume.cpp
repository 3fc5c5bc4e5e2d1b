// A resumed run never mixes two inputs (issue 12): every engine's checkpoint is keyed by the
// content of what determines its result, a checkpoint of other input is refused with a message
// that names what differs and how to start afresh, --fresh starts afresh, and an unchanged
// resume equals an uninterrupted run bit for bit. Edits tried between interrupt and resume: a
// number in the scene, a preset, an OBJ's vertex (the grid: test_vdb.cpp), and for the slab and
// sphere engines a coefficient and a preset; the `ssslab render` command end to end.
#include "core/error.h"
#include "core/film_image.h"
#include "core/hash.h"
#include "core/material.h"
#include "core/progress.h"
#include "core/scene.h"
#include "experiments/cli/common.h"
#include "mcml/engine.h"
#include "mcml/run_spec.h"
#include "testing.h"
#include "volpath/pencil.h"
#include "volpath/render.h"
#include "volpath/sphere.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace ssslab {
namespace {

namespace fs = std::filesystem;

TEST(KeyDifference, NamesChangedNewAndRemovedItems) {
    ContentKey a("k"), b("k");
    a.add("x", 1.0).add("y", std::array<double, 3>{0.1, 0.2, 0.3}).add("gone", 3.0);
    b.add("x", 1.0).add("y", std::array<double, 3>{0.1, 0.2, 0.4}).add("added", "s");
    EXPECT_EQ(key_difference(a.text(), a.text()), "");
    const std::string d = key_difference(a.text(), b.text());
    EXPECT_NE(d.find("y: was 0.1, 0.2, 0.3, now 0.1, 0.2, 0.4"), std::string::npos) << d;
    EXPECT_NE(d.find("gone = 3: only in the earlier input"), std::string::npos) << d;
    EXPECT_NE(d.find("added = s: new"), std::string::npos) << d;
    EXPECT_EQ(d.find("x:"), std::string::npos) << d;
    // A content hash is not spelled out.
    ContentKey h1("k"), h2("k");
    h1.add("mesh", hash_hex("a"));
    h2.add("mesh", hash_hex("b"));
    EXPECT_EQ(key_difference(h1.text(), h2.text()), "mesh: content changed");
    // Many differences: the first few, then a count.
    ContentKey m1("k"), m2("k");
    for (int i = 0; i < 7; ++i) {
        m1.add("v" + std::to_string(i), i);
        m2.add("v" + std::to_string(i), i + 1);
    }
    EXPECT_NE(key_difference(m1.text(), m2.text()).find("and 3 more"), std::string::npos);
}

// ---- the renderer -----------------------------------------------------------------------------

// An octahedron as OBJ (outward, counter-clockwise), vertex 1 at (1 + dx, 0, 0).
std::string octahedron_obj(double dx) {
    std::string s = "v " + std::to_string(1 + dx) + " 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\n" +
                    "v 0 0 1\nv 0 0 -1\n";
    // Faces (x, y, z) with x in {1, 2}, y in {3, 4}, z in {5, 6}: outward when the signs'
    // product is positive in this order, else swapped.
    for (int x : {1, 2})
        for (int y : {3, 4})
            for (int z : {5, 6}) {
                const int sign = (x == 1 ? 1 : -1) * (y == 3 ? 1 : -1) * (z == 5 ? 1 : -1);
                s += sign > 0 ? "f " + std::to_string(x) + " " + std::to_string(y) + " " +
                                    std::to_string(z) + "\n"
                              : "f " + std::to_string(x) + " " + std::to_string(z) + " " +
                                    std::to_string(y) + "\n";
            }
    return s;
}

std::string scene_text(const std::string& radiance, const std::string& preset) {
    return R"([scene]
name = "r"
[camera]
position = [0, 0, 10]
target = [0, 0, 0]
fov_y_deg = 40
width = 12
height = 12
[[lights]]
type = "environment"
radiance = )" +
           radiance +
           R"(
[[materials]]
name = "m"
preset = ")" +
           preset +
           R"("
roughness = 0.3
[[materials]]
name = "d"
type = "diffuse"
albedo = 0.5
[[shapes]]
type = "sphere"
radius = 1.2
subdivisions = 3
material = "m"
translate = [-1.5, 0, 0]
[[shapes]]
type = "mesh"
file = "o.obj"
material = "d"
translate = [1.6, 0, 0]
)";
}

volpath::RenderOptions render_options(const fs::path& ckpt) {
    volpath::RenderOptions o;
    o.budget.samples = 30;
    o.threads = 2;
    o.checkpoint_path = ckpt.string();
    o.checkpoint_seconds = 0;
    return o;
}

// Renders until at least 9 spp are done, then interrupts: the checkpoint stays behind.
void interrupt_render(const Scene& s, const fs::path& ckpt) {
    std::atomic<bool> cancel{false};
    volpath::RenderOptions o = render_options(ckpt);
    o.cancel = &cancel;
    o.on_batch = [&](const BatchProgress& p) {
        if (p.samples >= 9) cancel = true;
    };
    const volpath::RenderResult r = volpath::render(s, o);
    ASSERT_TRUE(r.interrupted);
    ASSERT_TRUE(fs::exists(ckpt));
}

struct SceneEdit {
    const char* what;
    std::string radiance = "2", preset = "Marble";
    double obj_dx = 0;
    const char* named;  // the item the refusal must name
};

TEST(ResumeRender, AnEditedSceneIsRefusedNamingWhatChangedAndFreshStartsAfresh) {
    const std::vector<SceneEdit> edits = {
        {"a number (the environment's radiance)", "20", "Marble", 0,
         "lights[0].color: was 2, 2, 2"},
        {"a preset", "2", "Ketchup", 0, "materials[0].sigma_a_per_cm"},
        {"an OBJ vertex", "2", "Marble", 0.25, "shapes[1].mesh: content changed"},
    };
    for (const SceneEdit& e : edits) {
        SCOPED_TRACE(e.what);
        testing::TempDir dir;
        dir.write("o.obj", octahedron_obj(0));
        dir.write("s.toml", scene_text("2", "Marble"));
        const fs::path ckpt = dir / "r.ckpt";
        interrupt_render(read_scene((dir / "s.toml").string()), ckpt);

        dir.write("o.obj", octahedron_obj(e.obj_dx));
        dir.write("s.toml", scene_text(e.radiance, e.preset));
        const Scene edited = read_scene((dir / "s.toml").string());
        try {
            (void)volpath::render(edited, render_options(ckpt));
            ADD_FAILURE() << "the checkpoint of the old scene was resumed";
        } catch (const InputError& err) {
            const std::string m = err.what();
            EXPECT_NE(m.find(e.named), std::string::npos) << m;
            EXPECT_NE(m.find("--fresh"), std::string::npos) << m;
            EXPECT_NE(m.find("r.ckpt"), std::string::npos) << m;
        }
        // --fresh: the edited scene alone, the same as an uninterrupted render of it.
        volpath::RenderOptions f = render_options(ckpt);
        f.fresh = true;
        const volpath::RenderResult afresh = volpath::render(edited, f);
        EXPECT_FALSE(afresh.run.resumed);
        volpath::RenderOptions plain = render_options("");
        plain.checkpoint_path.clear();
        const volpath::RenderResult whole = volpath::render(edited, plain);
        EXPECT_EQ(afresh.run.mean, whole.run.mean);
        EXPECT_EQ(afresh.run.se, whole.run.se);
        // The finished run's checkpoint is now the edited scene's (its caller removes it once
        // the image is stored): the edited scene resumes from it without a refusal.
        ASSERT_TRUE(fs::exists(ckpt));
        EXPECT_EQ(volpath::render(edited, render_options(ckpt)).run.mean, whole.run.mean);
    }
}

TEST(ResumeRender, AnUnchangedSceneResumesToTheUninterruptedImageAndSaysFromWhere) {
    testing::TempDir dir;
    dir.write("o.obj", octahedron_obj(0));
    dir.write("s.toml", scene_text("2", "Marble"));
    const Scene s = read_scene((dir / "s.toml").string());
    const fs::path ckpt = dir / "r.ckpt";
    interrupt_render(s, ckpt);
    // Reading the scene again (a new process would) gives the same key.
    const Scene again = read_scene((dir / "s.toml").string());
    volpath::RenderOptions o = render_options(ckpt);
    std::uint64_t from = 0;
    o.on_resume = [&](const BatchProgress& p) { from = p.samples; };
    const volpath::RenderResult resumed = volpath::render(again, o);
    EXPECT_TRUE(resumed.run.resumed);
    EXPECT_GE(from, 9u);
    EXPECT_LT(from, 30u);
    volpath::RenderOptions plain = render_options("");
    plain.checkpoint_path.clear();
    const volpath::RenderResult whole = volpath::render(s, plain);
    EXPECT_EQ(resumed.spp, whole.spp);
    EXPECT_EQ(resumed.run.mean, whole.run.mean);
    EXPECT_EQ(resumed.run.se, whole.run.se);
}

TEST(ResumeRender, TheKeyHoldsTheResolvedSceneNotItsSpelling) {
    // The same scene written differently (a comment, a number spelled 2.0, keys reordered)
    // has the same key; any change of a value that renders does not.
    testing::TempDir dir;
    dir.write("o.obj", octahedron_obj(0));
    dir.write("a.toml", scene_text("2", "Marble"));
    dir.write("b.toml", "# a comment\n" + scene_text("2.0", "marble"));
    volpath::RenderOptions o;
    EXPECT_EQ(volpath::render_fingerprint(read_scene((dir / "a.toml").string()), o),
              volpath::render_fingerprint(read_scene((dir / "b.toml").string()), o));
    dir.write("c.toml", scene_text("[2, 2, 2.0000001]", "Marble"));
    EXPECT_NE(volpath::render_fingerprint(read_scene((dir / "a.toml").string()), o),
              volpath::render_fingerprint(read_scene((dir / "c.toml").string()), o));
    volpath::RenderOptions seeded;
    seeded.seed = 2;
    EXPECT_NE(volpath::render_fingerprint(read_scene((dir / "a.toml").string()), o),
              volpath::render_fingerprint(read_scene((dir / "a.toml").string()), seeded));
}

// ---- the slab and sphere engines ------------------------------------------------------------

TEST(ResumeSlabEngines, AnEditedMediumIsRefusedNamingWhatChanged) {
    const Medium skin = *find_material("Skin1");
    Medium edited = skin;
    edited.sigma_s_per_cm[1] *= 1.001;
    const Medium other = *find_material("Ketchup");
    for (const auto& [label, m2, named] :
         {std::tuple{"a coefficient", edited, "medium.sigma_s_per_cm"},
          std::tuple{"a preset", other, "medium.sigma_a_per_cm"}}) {
        SCOPED_TRACE(label);
        testing::TempDir dir;
        volpath::PencilOptions o;
        o.budget.samples = 40000;
        o.batch_paths = 1000;
        o.checkpoint_prefix = (dir / "p").string();
        o.checkpoint_seconds = 0;
        std::atomic<bool> cancel{false};
        o.cancel = &cancel;
        o.on_batch = [&](int, const BatchProgress& p) {
            if (p.samples >= 5000) cancel = true;
        };
        ASSERT_TRUE(volpath::simulate_pencil(skin, {0.01, 20}, o).interrupted);
        o.cancel = nullptr;
        o.on_batch = nullptr;
        try {
            (void)volpath::simulate_pencil(m2, {0.01, 20}, o);
            ADD_FAILURE() << "resumed the checkpoint of another medium";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("--fresh"), std::string::npos) << e.what();
        }
        o.fresh = true;
        EXPECT_FALSE(volpath::simulate_pencil(m2, {0.01, 20}, o).interrupted);
    }
}

TEST(ResumeSlabEngines, McmlRefusesAnEditedLayerNamingIt) {
    const Medium skin = *find_material("Skin1");
    mcml::Grid g;
    g.dz = 0.01;
    g.dr = 0.01;
    g.nz = 20;
    g.nr = 20;
    g.na = 1;
    const mcml::RunSpec run = mcml::run_for_channel(skin, 0, 200000, g);
    mcml::RunSpec edited = run;
    edited.layers[1].mus *= 1.0001;
    testing::TempDir dir;
    mcml::EngineOptions o;
    o.batch_photons = 2000;
    o.checkpoint_path = (dir / "m.ckpt").string();
    o.checkpoint_seconds = 0;
    std::atomic<bool> cancel{false};
    o.cancel = &cancel;
    int seen = 0;
    o.on_batch = [&](const BatchProgress&) {
        if (++seen == 5) cancel = true;
    };
    ASSERT_EQ(mcml::run_default(run, o).reason, BatchStop::kInterrupted);
    o.cancel = nullptr;
    o.on_batch = nullptr;
    try {
        (void)mcml::run_default(edited, o);
        ADD_FAILURE() << "resumed the checkpoint of another layer";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("layer1.mus"), std::string::npos) << e.what();
    }
    std::uint64_t from = 0;
    o.on_resume = [&](const BatchProgress& p) { from = p.samples; };
    EXPECT_EQ(mcml::run_default(run, o).reason, BatchStop::kSamples);
    EXPECT_GE(from, 10000u);
}

TEST(ResumeSlabEngines, SphereRefusesAnEditedMediumNamingIt) {
    volpath::SphereScene sc;
    sc.medium = *find_material("Skin1");
    sc.radius_cm = 0.5;
    volpath::SphereScene edited = sc;
    edited.medium.g[2] = 0.1;
    testing::TempDir dir;
    volpath::SphereOptions o;
    o.budget.samples = 40000;
    o.batch_paths = 1000;
    o.checkpoint_prefix = (dir / "s").string();
    o.checkpoint_seconds = 0;
    std::atomic<bool> cancel{false};
    o.cancel = &cancel;
    o.on_batch = [&](int, const BatchProgress& p) {
        if (p.samples >= 3000) cancel = true;
    };
    ASSERT_TRUE(volpath::simulate_sphere(sc, o).interrupted);
    o.cancel = nullptr;
    o.on_batch = nullptr;
    try {
        (void)volpath::simulate_sphere(edited, o);
        ADD_FAILURE() << "resumed the checkpoint of another medium";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("medium.g"), std::string::npos) << e.what();
    }
}

// ---- progress lines -----------------------------------------------------------------------

TEST(ResumeProgress, TheRateAfterAResumeCountsOnlyThisRunsWork) {
    ::setenv("SSSLAB_PROGRESS", "1", 1);
    ::testing::internal::CaptureStderr();
    {
        Progress p("x", 300, "spp");
        p.resume_from(174);
        std::this_thread::sleep_for(std::chrono::milliseconds(60));
        p.update(177);  // 3 spp in >= 60 ms: at most 50 spp/s
    }
    const std::string line = ::testing::internal::GetCapturedStderr();
    ::unsetenv("SSSLAB_PROGRESS");
    const std::size_t at = line.find("(59.0%)  ");
    ASSERT_NE(at, std::string::npos) << line;
    const double rate = std::stod(line.substr(at + 9));
    EXPECT_LE(rate, 50.0) << line;  // 177 / elapsed would be thousands
}

TEST(ResumeProgress, NoErrorFigureBeforeOneExists) {
    EXPECT_EQ(cli::error_figure("rel.err", 0.3, 0.0), "");  // one batch: no standard error yet
    EXPECT_EQ(cli::error_figure("rel.err", 0.0, 0.1), "");
    EXPECT_EQ(cli::error_figure("rel.err", 0.5, 0.01), "rel.err 2%");
}

// ---- `ssslab render` end to end ---------------------------------------------------------------

struct Spawned {
    int exit_code = -1;
    std::string err;
};

// Starts `ssslab args` in `cwd` with a progress line on stderr, waits for the first progress
// line (a batch is done), sends SIGINT and waits for the exit.
Spawned run_and_interrupt(const std::vector<std::string>& args, const fs::path& cwd,
                          bool interrupt = true, const std::string& progress_unit = " spp") {
    const std::string bin = testing::ssslab_binary();
    const fs::path err_file = cwd / "stderr.txt";
    std::vector<std::string> argv_s = {bin};
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& s : argv_s) argv.push_back(s.data());
    argv.push_back(nullptr);
    std::vector<std::string> env_s = {"SSSLAB_PROGRESS=1"};
    for (char** e = environ; *e; ++e)
        if (std::string(*e).rfind("SSSLAB_PROGRESS=", 0) != 0) env_s.push_back(*e);
    std::vector<char*> envp;
    for (auto& s : env_s) envp.push_back(s.data());
    envp.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 2, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    const fs::path old = fs::current_path();
    fs::current_path(cwd);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, bin.c_str(), &fa, nullptr, argv.data(), envp.data());
    fs::current_path(old);
    posix_spawn_file_actions_destroy(&fa);
    Spawned out;
    if (rc != 0) return out;
    const auto t0 = std::chrono::steady_clock::now();
    while (interrupt && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
        if (testing::read_text(err_file).find(progress_unit) != std::string::npos) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (interrupt) ::kill(pid, SIGINT);
    int status = 0;
    ::waitpid(pid, &status, 0);
    out.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    out.err = testing::read_text(err_file);
    fs::remove(err_file);
    return out;
}

TEST(ResumeProgress, TheCommandsFirstProgressLineHasNoErrorFigure) {
    // The first line is drawn after one batch (3 spp): no standard error exists yet.
    testing::TempDir dir;
    dir.write("o.obj", octahedron_obj(0));
    dir.write("s.toml", scene_text("2", "Marble"));
    const auto r = run_and_interrupt({"render", "s.toml", "--spp", "30", "--out", "m.exr"},
                                     dir.path(), /*interrupt=*/false);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::size_t first = r.err.find("3/30 spp");
    ASSERT_NE(first, std::string::npos) << r.err;
    const std::string line = r.err.substr(first, r.err.find('\r', first) - first);
    EXPECT_EQ(line.find("rel.err"), std::string::npos) << line;
    EXPECT_EQ(r.err.find("rel.err 0%"), std::string::npos) << r.err;
}

TEST(ResumeRenderCommand, RefusesAnEditedSceneResumesAnUnchangedOneAndWritesItsProvenance) {
    testing::TempDir dir, whole;
    for (const auto* d : {&dir, &whole}) {
        d->write("o.obj", octahedron_obj(0));
        d->write("s.toml", scene_text("2", "Marble"));
    }
    // Batches of 6 spp; the resumed command gives no batch size (its budget alone would make
    // it 3): it keeps the checkpoint's.
    const auto cut = run_and_interrupt({"render", "s.toml", "--spp", "3000000", "--batch-spp", "6",
                                        "--threads", "2", "--out", "m.exr"},
                                       dir.path());
    ASSERT_EQ(cut.exit_code, 130) << cut.err;
    const std::size_t at = cut.err.find("interrupted after ");
    ASSERT_NE(at, std::string::npos) << cut.err;
    const long done = std::stol(cut.err.substr(at + 18));
    ASSERT_GT(done, 0);
    EXPECT_EQ(dir.files(), (std::vector<std::string>{"m.exr.ckpt", "o.obj", "s.toml"}));
    const std::string spp = std::to_string(done + 3);
    const std::vector<std::string> args = {"render",    "s.toml", "--spp", spp,
                                           "--threads", "2",      "--out", "m.exr"};

    // Edited between interrupt and resume: refused, exit 2, nothing written.
    dir.write("s.toml", scene_text("2", "Ketchup"));
    const auto refused = testing::run_ssslab(args, dir.path());
    EXPECT_EQ(refused.exit_code, 2) << refused.err;
    EXPECT_NE(refused.err.find("materials[0].sigma_a_per_cm"), std::string::npos) << refused.err;
    EXPECT_NE(refused.err.find("--fresh"), std::string::npos) << refused.err;
    EXPECT_EQ(dir.files(), (std::vector<std::string>{"m.exr.ckpt", "o.obj", "s.toml"}));

    // Restored: resumes, says from where (also when stderr is a log, not a terminal), and
    // equals an uninterrupted run bit for bit.
    dir.write("s.toml", scene_text("2", "Marble"));
    const auto resumed = testing::run_ssslab(args, dir.path());
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    EXPECT_NE(resumed.err.find("resuming from " + std::to_string(done) + " of " + spp + " spp"),
              std::string::npos)
        << resumed.err;
    std::vector<std::string> whole_args = args;
    whole_args.insert(whole_args.end(), {"--batch-spp", "6"});
    const auto full = testing::run_ssslab(whole_args, whole.path());
    ASSERT_EQ(full.exit_code, 0) << full.err;
    const LayeredImage a = read_exr((dir / "m.exr").string());
    const LayeredImage b = read_exr((whole / "m.exr").string());
    for (const char* layer : {"radiance", "radiance.stderr", "subsurface", "specular"}) {
        const auto pa = a.layer(layer).pixels(), pb = b.layer(layer).pixels();
        ASSERT_EQ(pa.size(), pb.size());
        EXPECT_TRUE(std::equal(pa.begin(), pa.end(), pb.begin())) << layer;
    }
    EXPECT_FALSE(fs::exists(dir / "m.exr.ckpt"));

    // Provenance beside the image and in its header.
    const std::string toml = testing::read_text(dir / "m.exr.toml");
    for (const std::string& s :
         std::vector<std::string>{"[provenance]", "git_revision", "command_line",
                                  "resumed_from_spp = " + std::to_string(done), "preset = 'Marble'",
                                  "[render]", "seed = 1", "content_key", "median_pixel_rel_se"})
        EXPECT_NE(toml.find(s), std::string::npos) << s << "\n" << toml;
    EXPECT_NE(testing::read_text(whole / "m.exr.toml").find("resumed_from_spp = 0"),
              std::string::npos);
    for (const char* k : {"ssslab.git_revision", "ssslab.command_line", "ssslab.content_key",
                          "ssslab.provenance", "ssslab.scene_file"})
        EXPECT_TRUE(a.metadata().count(k)) << k;
    EXPECT_NE(a.metadata().at("ssslab.provenance").find("preset = 'Marble'"), std::string::npos);

    // --fresh on an edited scene: starts afresh.
    const auto cut2 = run_and_interrupt(
        {"render", "s.toml", "--spp", "3000000", "--threads", "2", "--out", "m.exr"}, dir.path());
    ASSERT_EQ(cut2.exit_code, 130) << cut2.err;
    dir.write("s.toml", scene_text("20", "Marble"));
    std::vector<std::string> fresh = args;
    fresh.push_back("--fresh");
    const auto afresh = testing::run_ssslab(fresh, dir.path());
    ASSERT_EQ(afresh.exit_code, 0) << afresh.err;
    EXPECT_EQ(afresh.err.find("resuming"), std::string::npos) << afresh.err;
    EXPECT_NE(testing::read_text(dir / "m.exr.toml").find("resumed_from_spp = 0"),
              std::string::npos);
}

TEST(ResumeCommands, McmlProfileAndSphereRefuseAnEditedInputAndStartAfreshWithFresh) {
    struct Case {
        const char* command;
        std::vector<std::string> args;  // with a budget that cannot finish before the signal
        const char* unit;               // what the progress line counts
        const char* file;               // the input edited between interrupt and resume
        std::string before, after;
        std::vector<const char*> named;  // the refusal names these
        const char* checkpoint;
    };
    const std::string mci = testing::read_text(testing::data_path("mcml-1.2.2/b_giov_n15.mci"));
    const std::vector<Case> cases = {
        {"mcml",
         {"mcml", "b.mci", "--photons", "2000000000", "--batch", "5000", "--threads", "2"},
         " photons",
         "b.mci",
         mci,
         std::regex_replace(mci, std::regex("1.5     10      90 "), "1.5     10      95 "),
         {"layer1.mus: was 90, now 95"},
         "b_giov_n15.mco.ckpt"},
        {"profile",
         {"profile", "--config", "c.toml", "--photons", "2000000000", "--batch", "5000",
          "--threads", "2", "--out", "p.csv"},
         " photons",
         "c.toml",
         "[material]\npreset = \"Skin1\"\n",
         "[material]\npreset = \"Marble\"\n",
         {"layer1.mua: was", "p.csv.R.ckpt"},
         "p.csv.R.ckpt"},
        {"sphere",
         {"sphere", "--config", "c.toml", "--photons", "2000000000", "--batch", "5000", "--threads",
          "2", "--out", "s"},
         " paths",
         "c.toml",
         "[material]\npreset = \"Skin1\"\n",
         "[material]\nsigma_a_per_mm = 0.01\nsigma_s_per_mm = 1\ng = 0\neta = 1.3\n",
         {"medium.sigma_a_per_cm: was", "s.R.ckpt"},
         "s.R.ckpt"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.command);
        testing::TempDir dir;
        dir.write(c.file, c.before);
        const auto cut = run_and_interrupt(c.args, dir.path(), true, c.unit);
        ASSERT_EQ(cut.exit_code, 130) << cut.err;
        ASSERT_TRUE(fs::exists(dir / c.checkpoint)) << cut.err;
        dir.write(c.file, c.after);
        const auto refused = testing::run_ssslab(c.args, dir.path());
        EXPECT_EQ(refused.exit_code, 2) << refused.err;
        for (const char* n : c.named)
            EXPECT_NE(refused.err.find(n), std::string::npos) << refused.err;
        EXPECT_NE(refused.err.find("--fresh"), std::string::npos) << refused.err;
        // --fresh with a small budget: starts afresh and finishes.
        std::vector<std::string> fresh = c.args;
        fresh[std::find(fresh.begin(), fresh.end(), std::string("--photons")) - fresh.begin() + 1] =
            "20000";
        fresh.push_back("--fresh");
        const auto afresh = testing::run_ssslab(fresh, dir.path());
        EXPECT_EQ(afresh.exit_code, 0) << afresh.err;
        EXPECT_EQ(afresh.err.find("resuming"), std::string::npos) << afresh.err;
        EXPECT_FALSE(fs::exists(dir / c.checkpoint));
    }
}

}  // namespace
}  // namespace ssslab
