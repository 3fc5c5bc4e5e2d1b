// [outputs.realtime] (experiments/runner/studies/realtime/realtime_study.cpp): a small experiment
// end to end through `ssslab run`: the tables a script reads, the metrics `ssslab check` compares,
// the report's flip viewer driven in headless Chromium, and its config errors.
#include "core/build_info.h"
#include "experiments/runner/plots.h"
#include "testing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab {
namespace {

namespace fs = std::filesystem;
using testing::run_ssslab;

// The ball of test_frame.cpp (testing.h), a narrower view on a smaller image.
const std::string kScene = testing::ball_scene(25, 40, 32);

std::string config(const std::string& models) {
    return R"([experiment]
name = "rt"
title = "t"
seed = 3
[outputs.realtime]
scenes = ["ball.toml"]
models = )" +
           models +
           R"(
taps = 9
sweep_models = ["svd:rank=1"]
taps_sweep = [5, 9]
jitter = 0.33
width = 0
height = 0
spp = 12
photons = 2000
light_samples = 2
environment_samples = 4
shadow_map_size = 128
reference_samples = 16
munoz = ["layers=1", "layers=3,t=0.001,downsample=2,kernel=average"]
jensen_buhler = ["density=2,threshold=0.1", "density=2,threshold=0,bound=box",
                 "density=2,threshold=0.1,profile=dipole"]
)";
}

class RealtimeStudy : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        dir_ = new testing::TempDir;
        dir_->write("ball.toml", kScene);
        dir_->write("rt.toml", config(R"(["svd:rank=1", "preintegration"])"));
        const auto r = run_ssslab({"run", "rt.toml", "-q"}, dir_->path());
        ok_ = r.exit_code == 0;
        err_ = r.out + r.err;
    }
    static void TearDownTestSuite() {
        delete dir_;
        dir_ = nullptr;
    }
    void SetUp() override { ASSERT_TRUE(ok_) << err_; }
    static fs::path out() { return dir_->path() / "results" / "rt"; }

    static testing::TempDir* dir_;
    static bool ok_;
    static std::string err_;
};
testing::TempDir* RealtimeStudy::dir_ = nullptr;
bool RealtimeStudy::ok_ = false;
std::string RealtimeStudy::err_;

std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
    std::vector<std::vector<std::string>> rows;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        // RFC 4180 fields: quoted where they hold a comma or a quote ("" inside).
        std::vector<std::string> cells(1);
        bool quoted = false;
        for (size_t i = 0; i < line.size(); ++i) {
            const char ch = line[i];
            if (quoted && ch == '"' && i + 1 < line.size() && line[i + 1] == '"')
                cells.back() += '"', ++i;
            else if (ch == '"')
                quoted = !quoted;
            else if (ch == ',' && !quoted)
                cells.emplace_back();
            else
                cells.back() += ch;
        }
        rows.push_back(cells);
    }
    return rows;
}

size_t column(const std::vector<std::string>& header, const std::string& name) {
    for (size_t i = 0; i < header.size(); ++i)
        if (header[i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return 0;
}

TEST_F(RealtimeStudy, TablesNameTheirColumnsAndHoldEveryModelAndChannel) {
    const auto t = csv_rows(testing::read_text(out() / "realtime" / "table_6_4.csv"));
    ASSERT_EQ(t.size(), 1u + 2 * 3);  // header, 2 models x 3 channels
    const auto& h = t[0];
    const size_t ref = column(h, "rms_vs_reference"), vp = column(h, "rms_vs_volpath"),
                 vpse = column(h, "rms_vs_volpath_se"), raw = column(h, "raw_rms_vs_volpath"),
                 noise = column(h, "volpath_noise_rms"), norm = column(h, "norm_table");
    double max_norm = 0;
    for (size_t i = 1; i < t.size(); ++i) {
        EXPECT_EQ(t[i][0], "ball");
        EXPECT_GE(std::stod(t[i][ref]), 0);
        EXPECT_GE(std::stod(t[i][vpse]), 0);
        // Noise correction: corrected^2 = raw^2 - noise^2 (to the digits written), when > 0.
        const double c = std::stod(t[i][vp]), r = std::stod(t[i][raw]), n = std::stod(t[i][noise]);
        if (c > 0) {
            EXPECT_NEAR(c * c, r * r - n * n, 1e-4 * r * r);
        }
        max_norm = std::max(max_norm, std::stod(t[i][norm]));
    }
    EXPECT_DOUBLE_EQ(max_norm, 1.0);  // Table 6.4's normalisation: the largest error is 1
    const auto s = csv_rows(testing::read_text(out() / "realtime" / "error_vs_time.csv"));
    // 2 table models, then svd:rank=1 at 5 taps (jitter 0 and 0.33) and 9 taps jittered.
    ASSERT_EQ(s.size(), 1u + 2 + 3);
    EXPECT_EQ(s[3][column(s[0], "taps")], "5");
    EXPECT_EQ(s[4][column(s[0], "jitter")], "0.33");
    EXPECT_TRUE(fs::exists(out() / "realtime" / "decomposition.csv"));
    EXPECT_TRUE(fs::exists(out() / "realtime" / "thesis_table_6_4.csv"));
    const std::string m = testing::read_text(out() / "metrics.csv");
    for (const char* name :
         {"ball.svd_rank1.R.rms_vs_reference", "ball.preintegration.B.rms_vs_volpath",
          "ball.reference.G.rms_vs_volpath"})
        EXPECT_NE(m.find(name), std::string::npos) << name;
    for (const char* png : {"volpath.png", "reference.png", "svd_rank1.png", "diff_svd_rank1.png",
                            "cut_preintegration.png", "cutdiff_preintegration.png"})
        EXPECT_TRUE(fs::exists(out() / "realtime" / "ball" / png)) << png;
}

// Munoz11's variants (munoz = [...]): a row per scene and variant with its parameters, errors
// with standard errors and time.
TEST_F(RealtimeStudy, MunozVariantsAreScoredLikeTheModels) {
    const auto t = csv_rows(testing::read_text(out() / "realtime" / "munoz11.csv"));
    ASSERT_EQ(t.size(), 1u + 2);
    const auto& h = t[0];
    EXPECT_EQ(t[1][column(h, "variant")],
              "layers=1 t=0 downsample=1 split=equal visible=skip kernel=point");
    EXPECT_EQ(t[2][column(h, "layers")], "3");
    EXPECT_EQ(t[2][column(h, "threshold")], "0.001");
    EXPECT_EQ(t[2][column(h, "downsample")], "2");
    for (size_t i = 1; i < t.size(); ++i) {
        EXPECT_EQ(t[i][0], "ball");
        for (const char* c : {"rms_vs_reference", "rms_vs_volpath", "rms_vs_volpath_se", "seconds"})
            EXPECT_GE(std::stod(t[i][column(h, c)]), 0) << c;
        // A different method from the screen-space reference (the path tracer's 12 spp may
        // hide the error: noise-corrected, it can be 0).
        EXPECT_GT(std::stod(t[i][column(h, "rms_vs_reference")]), 0);
        EXPECT_GT(std::stoll(t[i][column(h, "convolutions")]), 0);
    }
}

// Jensen-Buhler's variants (jensen_buhler = [...]): a row per scene and variant in
// jensen_buhler.csv (the threshold, the cloud's points, errors, seconds); variants of one density
// share the cloud; and approximations.csv lists every method of the scene once: the screen-space
// reference, the models, the Munoz and Jensen-Buhler variants.
TEST_F(RealtimeStudy, JensenBuhlerVariantsAndTheTableOfEveryApproximation) {
    const auto t = csv_rows(testing::read_text(out() / "realtime" / "jensen_buhler.csv"));
    ASSERT_EQ(t.size(), 1u + 3);
    const auto& h = t[0];
    for (const char* c :
         {"scene", "threshold", "points", "rms_vs_volpath", "rms_vs_volpath_se", "seconds"})
        EXPECT_LT(column(h, c), 6u) << c;
    EXPECT_EQ(t[1][column(h, "threshold")], "0.1");
    EXPECT_EQ(t[2][column(h, "threshold")], "0");
    EXPECT_EQ(t[2][column(h, "bound")], "box");
    EXPECT_EQ(t[3][column(h, "profile")], "dipole");
    for (size_t i = 1; i < t.size(); ++i) {
        EXPECT_EQ(t[i][0], "ball");
        EXPECT_EQ(t[i][column(h, "points")], t[1][column(h, "points")]);
        EXPECT_GT(std::stoll(t[i][column(h, "points")]), 100);
        for (const char* c : {"rms_vs_volpath", "rms_vs_volpath_se", "seconds", "query_seconds"})
            EXPECT_GE(std::stod(t[i][column(h, c)]), 0) << c;
        EXPECT_GT(std::stod(t[i][column(h, "rms_vs_reference")]), 0);
        EXPECT_GT(std::stoll(t[i][column(h, "nodes_visited")]), 0);
    }
    // Threshold 0: every point summed, no cluster.
    EXPECT_EQ(t[2][column(h, "clusters")], "0");
    EXPECT_GT(std::stoll(t[1][column(h, "clusters")]), 0);

    const auto a = csv_rows(testing::read_text(out() / "realtime" / "approximations.csv"));
    const auto& ah = a[0];
    for (const char* c : {"scene", "method", "rms_vs_volpath", "rms_vs_volpath_se", "seconds"})
        EXPECT_LT(column(ah, c), 5u) << c;
    std::vector<std::string> methods;
    for (size_t i = 1; i < a.size(); ++i) {
        methods.push_back(a[i][column(ah, "method")]);
        EXPECT_GT(std::stod(a[i][column(ah, "seconds")]), 0) << methods.back();
        EXPECT_GE(std::stod(a[i][column(ah, "rms_vs_volpath_se")]), 0) << methods.back();
    }
    const std::vector<std::string> want = {
        "reference:2d",
        "svd:rank=1",
        "preintegration",
        "munoz:layers=1,t=0,downsample=1,split=equal,visible=skip,kernel=point",
        "munoz:layers=3,t=0.001,downsample=2,split=equal,visible=skip,kernel=average",
        "jensen_buhler:density=2,threshold=0.1,bound=centre,profile=mc,candidates=5",
        "jensen_buhler:density=2,threshold=0,bound=box,profile=mc,candidates=5",
        "jensen_buhler:density=2,threshold=0.1,bound=centre,profile=dipole,candidates=5"};
    EXPECT_EQ(methods, want);
    // The relative bias of the total light: 0 for the reference against itself; against the
    // path tracer with a positive standard error.
    EXPECT_EQ(std::stod(a[1][column(ah, "bias_vs_reference")]), 0.0);
    for (size_t i = 1; i < a.size(); ++i) {
        EXPECT_TRUE(std::isfinite(std::stod(a[i][column(ah, "bias_vs_volpath")])));
        EXPECT_GT(std::stod(a[i][column(ah, "bias_vs_volpath_se")]), 0) << methods[i - 1];
    }
}

// Error against the SSS pass time as a figure per scene (scripts/plot.py, "error_vs_time"), in
// the realtime section with its caption; without matplotlib the section says why there is none.
TEST_F(RealtimeStudy, ErrorAgainstTimeIsPlottedInTheRealtimeSection) {
    const std::string html = testing::read_text(out() / "report.html");
    const size_t realtime = html.find("<h2 id=\"realtime\">");
    const size_t at = html.find("<h3 id=\"realtime-time\">Error against time</h3>");
    ASSERT_NE(realtime, std::string::npos);
    ASSERT_NE(at, std::string::npos);
    EXPECT_LT(realtime, at);
    EXPECT_EQ(html.find("<h2", realtime + 1), html.find("<h2 id=\"metrics\">"))
        << "the figure's heading is inside the realtime section";
    const std::string sec = html.substr(at, html.find("<h3", at + 1) - at);
    // The table the figure draws: the RGB errors with their standard errors, and the times.
    const auto s = csv_rows(testing::read_text(out() / "realtime" / "error_vs_time.csv"));
    ASSERT_GE(s.size(), 2u);
    const size_t vp = column(s[0], "rms_vs_volpath_rgb"),
                 vpse = column(s[0], "rms_vs_volpath_rgb_se"),
                 refse = column(s[0], "rms_vs_reference_rgb_se"), frame = column(s[0], "frame_ms"),
                 sss = column(s[0], "sss_ms");
    for (size_t i = 1; i < s.size(); ++i) {
        EXPECT_GT(std::stod(s[i][vpse]), 0) << "the path tracer's noise: " << i;
        EXPECT_GE(std::stod(s[i][refse]), 0);
        EXPECT_GE(std::stod(s[i][vp]), 0);
        EXPECT_GT(std::stod(s[i][frame]), std::stod(s[i][sss])) << "the frame holds the pass";
    }
    if (runner::find_python().empty()) {
        EXPECT_NE(sec.find("No plots: no Python with matplotlib"), std::string::npos) << sec;
        GTEST_SKIP() << "no python3 with matplotlib";
    }
    const fs::path stem = out() / "plots" / "realtime_error_vs_time_ball";
    for (const char* ext : {".png", ".svg", ".json"})
        ASSERT_TRUE(fs::exists(stem.string() + ext)) << ext << "\n" << sec;
    const testing::RgbImage png = testing::read_png(stem.string() + ".png");
    EXPECT_GT(png.width, 800) << "two panels side by side";
    EXPECT_GT(png.height, 300);
    EXPECT_EQ(sec.find("No plots"), std::string::npos) << sec;
    EXPECT_NE(sec.find("<figure><a href=\"plots/realtime_error_vs_time_ball.svg\"><img "
                       "src=\"plots/realtime_error_vs_time_ball.png\""),
              std::string::npos)
        << sec;
    const size_t cap = sec.find("<figcaption>ball: RMS error of the subsurface layer");
    ASSERT_NE(cap, std::string::npos) << sec;
    const std::string caption = sec.substr(cap, sec.find("</figcaption>", cap) - cap);
    for (const char* what :
         {"against the SSS pass time", "against the screen-space 2D reference",
          "against the path tracer", "dashed with jitter 0.33", "points labelled by taps",
          "The rest of these frames (raster, shadow maps and lighting"})
        EXPECT_NE(caption.find(what), std::string::npos) << what << "\n" << caption;
    // What the figure holds (plot.py's JSON beside it): the pass's time on x, a line per swept
    // model and jitter, the other models, no overlapping texts.
    const std::string j = testing::read_text(stem.string() + ".json");
    EXPECT_NE(j.find("\"x\": \"sss_ms\""), std::string::npos) << j;
    for (const char* series :
         {"\"svd:rank=1\"", "\"svd:rank=1, jitter 0.33\"", "\"preintegration\""})
        EXPECT_NE(j.find(series), std::string::npos) << series << "\n" << j;
    EXPECT_NE(j.find("\"overlapping_texts\": []"), std::string::npos) << j;
}

TEST_F(RealtimeStudy, TheFlipViewerWorksInHeadlessChromium) {
    if (!testing::have_chromium())
        GTEST_SKIP() << "chromium is not installed (scripts/setup.sh installs it)";
    // A copy of the report with a probe that clicks through the viewer and writes what it saw.
    std::string html = testing::read_text(out() / "report.html");
    const std::string probe =
        "<script>window.addEventListener('load', function () {"
        "var v = document.querySelector('div.flip'), b = v.querySelectorAll('button');"
        "var img = v.querySelector('img.view'), seen = [];"
        "b[2].click(); seen.push(img.getAttribute('src'));"
        "v.querySelector('input.diffmode').click(); seen.push(img.getAttribute('src'));"
        "v.dispatchEvent(new KeyboardEvent('keydown', {key: 'ArrowRight'}));"
        "seen.push(img.getAttribute('src'));"
        "var r = v.querySelector('input.exposure'); r.value = 2;"
        "r.dispatchEvent(new Event('input')); seen.push(img.style.filter);"
        "document.body.setAttribute('data-seen', seen.join('|'));"
        "document.body.setAttribute('data-ready', v.dataset.ready);"
        "});</script>";
    html.insert(html.rfind("</body>"), probe);
    const fs::path page = out() / "probe.html";
    {
        std::ofstream f(page);
        f << html;
    }
    const fs::path dom = dir_->path() / "dom.html", log = dir_->path() / "chromium.log";
    ASSERT_EQ(testing::chromium("--dump-dom", page, dir_->path(), "1280,2000", dom.string()), 0)
        << testing::read_text(log);
    const std::string d = testing::read_text(dom);
    EXPECT_NE(d.find("data-ready=\"yes\""), std::string::npos);
    EXPECT_NE(d.find("data-seen=\"realtime/ball/svd_rank1.png|realtime/ball/diff_svd_rank1.png|"
                     "realtime/ball/diff_preintegration.png|brightness(4)\""),
              std::string::npos)
        << d.substr(d.find("data-seen"), 300);
    const std::string console = testing::read_text(log);
    EXPECT_EQ(console.find("Uncaught"), std::string::npos) << console;
    EXPECT_EQ(console.find("Failed to load resource"), std::string::npos) << console;
}

// The same experiment with the SSS pass on the GL twin (backend = "gl"): every score of the
// table equals the software run's to 1e-5 relative (the twin's parity, tests/test_gl.cpp).
TEST_F(RealtimeStudy, TheGlBackendGivesTheSameScores) {
    if (!SSSLAB_HAVE_GL) GTEST_SKIP() << "built without the GL twin";
    testing::TempDir dir;
    dir.write("ball.toml", kScene);
    std::string cfg = config(R"(["svd:rank=1", "preintegration"])");
    cfg.replace(cfg.find("taps = 9"), 8, "taps = 9\nbackend = \"gl\"");
    dir.write("rt.toml", cfg);
    const auto r = run_ssslab({"run", "rt.toml", "-q"}, dir.path());
    if (r.exit_code != 0 && r.err.find("no OpenGL context") != std::string::npos)
        GTEST_SKIP() << r.err;
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
    const auto sw = csv_rows(testing::read_text(out() / "realtime" / "table_6_4.csv"));
    const auto gl =
        csv_rows(testing::read_text(dir.path() / "results" / "rt" / "realtime" / "table_6_4.csv"));
    ASSERT_EQ(gl.size(), sw.size());
    for (const char* name : {"rms_vs_reference", "rms_vs_volpath", "raw_rms_vs_volpath"}) {
        const size_t c = column(sw[0], name);
        for (size_t i = 1; i < sw.size(); ++i) {
            const double a = std::stod(sw[i][c]), b = std::stod(gl[i][c]);
            EXPECT_LE(std::fabs(a - b), 1e-5 * std::fabs(a)) << name << " row " << i;
        }
    }
}

TEST(RealtimeStudyConfig, BadModelsAndMaterialsAreLocated) {
    testing::TempDir dir;
    std::string scene = kScene;
    scene.replace(scene.find("preset = \"Skin1\""), 16,
                  "sigma_a_per_mm = 0.01\nsigma_s_per_mm = 1\ng = 0\neta = 1.3");
    dir.write("ball.toml", scene);
    dir.write("e.toml", config(R"(["svd:rank=1", "manual:table_a1,unit=mm"])"));
    auto r = run_ssslab({"run", "e.toml"}, dir.path());
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    EXPECT_NE(r.err.find("outputs.realtime.models"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("given by coefficients"), std::string::npos) << r.err;
    dir.write("e.toml", config(R"(["svd:rank=1", "svd:rank=1"])"));
    r = run_ssslab({"run", "e.toml"}, dir.path());
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("listed twice"), std::string::npos) << r.err;
    dir.write("e.toml", config(R"(["manual:fit=edge"])"));
    r = run_ssslab({"run", "e.toml"}, dir.path());
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("kernel study"), std::string::npos) << r.err;
    std::string cfg = config(R"(["svd:rank=1"])");
    cfg.replace(cfg.find("taps = 9"), 8, "taps = 9\nbackend = \"vulkan\"");
    dir.write("e.toml", cfg);
    r = run_ssslab({"run", "e.toml"}, dir.path());
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("outputs.realtime.backend"), std::string::npos) << r.err;
    for (const char* bad : {"\"layers=0\"", "\"layers=4,colour=red\"", "\"t=2\""}) {
        cfg = config(R"(["svd:rank=1"])");
        cfg.replace(cfg.find("munoz = ["), 9, std::string("munoz = [") + bad + ", ");
        dir.write("e.toml", cfg);
        r = run_ssslab({"run", "e.toml"}, dir.path());
        EXPECT_EQ(r.exit_code, 2) << bad;
        EXPECT_NE(r.err.find("outputs.realtime.munoz"), std::string::npos) << r.err;
    }
    for (const char* bad : {"\"threshold=-0.1\"", "\"density=0\"", "\"profile=dipol\"",
                            "\"density=2,threshold=0.1\""}) {
        cfg = config(R"(["svd:rank=1"])");
        cfg.replace(cfg.find("jensen_buhler = ["), 17,
                    std::string("jensen_buhler = [") + bad + ", ");
        dir.write("e.toml", cfg);
        r = run_ssslab({"run", "e.toml"}, dir.path());
        EXPECT_EQ(r.exit_code, 2) << bad;
        EXPECT_NE(r.err.find("outputs.realtime.jensen_buhler"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("e.toml:"), std::string::npos) << r.err;
    }
    EXPECT_FALSE(fs::exists(dir / "results"));
}

}  // namespace
}  // namespace ssslab
