// [outputs.realtime] (experiments/runner/realtime_study.h): a small experiment end to end through
// `ssslab run`: the tables a script reads, the metrics `ssslab check` compares, the report's flip
// viewer driven in headless Chromium, and its config errors.
#include "testing.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab {
namespace {

namespace fs = std::filesystem;
using testing::run_ssslab;

constexpr const char* kScene = R"(
[scene]
name = "ball"
[camera]
position = [0, 8, 40]
target = [0, 4, 0]
fov_y_deg = 25
width = 40
height = 32
[[lights]]
type = "sphere"
position = [20, 40, 20]
radius = 3
radiance = [40, 40, 40]
[[lights]]
type = "environment"
radiance = [0.05, 0.05, 0.05]
[[materials]]
name = "jelly"
preset = "Skin1"
roughness = 0.3
[[materials]]
name = "floor"
type = "diffuse"
albedo = [0.5, 0.5, 0.5]
[[shapes]]
type = "sphere"
radius = 4
subdivisions = 4
translate = [0, 4.1, 0]
material = "jelly"
[[shapes]]
type = "plane"
size_x = 100
size_z = 100
material = "floor"
)";

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
        std::vector<std::string> cells;
        std::istringstream l(line);
        for (std::string c; std::getline(l, c, ',');) cells.push_back(c);
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

TEST_F(RealtimeStudy, TheFlipViewerWorksInHeadlessChromium) {
    if (std::system("command -v chromium >/dev/null 2>&1") != 0)
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
    const std::string cmd =
        "chromium --headless=new --no-sandbox --disable-gpu --no-first-run "
        "--disable-background-networking --disable-component-update --disable-sync "
        "--virtual-time-budget=10000 --enable-logging=stderr --v=0 --user-data-dir=" +
        (dir_->path() / "profile").string() + " --dump-dom 'file://" + page.string() + "' >'" +
        dom.string() + "' 2>'" + log.string() + "'";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
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
    EXPECT_FALSE(fs::exists(dir / "results"));
}

}  // namespace
}  // namespace ssslab
