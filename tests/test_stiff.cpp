// The stiff sweep (experiments/stiff/sweep.toml, experiments/runner/stiff_study.h) at its quick
// budget: every engine and model on the extremes of its inputs, no NaN or Inf, energy within
// its standard error, every run ended by its budget. And the sweep's own checks can fail: a time
// cap too short for the budget stops the runs, and the sweep says so.
#include "core/error.h"
#include "experiments/runner/experiment.h"
#include "experiments/runner/report.h"
#include "experiments/runner/runner.h"
#include "testing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab {
namespace {

namespace fs = std::filesystem;

// The CSV's rows as header name -> cell.
std::vector<std::map<std::string, std::string>> read_csv(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    const auto cells = runner::parse_csv(ss.str());
    std::vector<std::map<std::string, std::string>> rows;
    for (size_t r = 1; r < cells.size(); ++r) {
        std::map<std::string, std::string> row;
        for (size_t i = 0; i < cells[0].size() && i < cells[r].size(); ++i)
            row[cells[0][i]] = cells[r][i];
        rows.push_back(row);
    }
    return rows;
}

std::string sweep_config(const std::string& extra = "") {
    std::ifstream in(testing::source_path("experiments/stiff/sweep.toml"));
    std::stringstream ss;
    ss << in.rdbuf();
    std::string t = ss.str();
    if (!extra.empty()) {
        const size_t at = t.find("seconds_cap = 300");
        EXPECT_NE(at, std::string::npos);
        t.replace(at, std::string("seconds_cap = 300").size(), extra);
    }
    return t;
}

std::vector<std::map<std::string, std::string>> run_sweep(const testing::TempDir& dir,
                                                          const std::string& text) {
    const runner::Experiment e = runner::parse_experiment(text, "sweep.toml");
    runner::RunOptions o;
    o.quick = true;
    o.quiet = true;
    o.results_root = dir / "results";
    runner::ExperimentRun r = runner::plan(e, o);
    EXPECT_TRUE(runner::execute(r, o));
    return read_csv(dir / "results" / "stiff-sweep" / "stiff" / "sweep.csv");
}

TEST(StiffSweep, EveryEngineAndModelStaysFiniteConservesEnergyAndEnds) {
    testing::TempDir dir;
    const auto rows = run_sweep(dir, sweep_config());
    std::set<std::string> engines, axes;
    int failed = 0, stochastic = 0;
    double worst_z = 0;
    for (const auto& r : rows) {
        engines.insert(r.at("engine").substr(0, r.at("engine").find(' ')));
        axes.insert(r.at("axis"));
        EXPECT_EQ(r.at("refused"), "0")
            << r.at("engine") << " " << r.at("value") << ": " << r.at("note");
        EXPECT_EQ(r.at("nonfinite"), "0") << r.at("engine") << " " << r.at("value");
        EXPECT_EQ(r.at("out_of_range"), "0") << r.at("engine") << " " << r.at("value");
        EXPECT_EQ(r.at("ended"), "1") << r.at("engine") << " " << r.at("value");
        if (r.at("pass") != "1") {
            ++failed;
            ADD_FAILURE() << r.at("engine") << " | " << r.at("axis") << " " << r.at("value")
                          << " | " << r.at("quantity") << ": " << r.at("estimate") << " +- "
                          << r.at("se") << " against " << r.at("expected") << " (z " << r.at("z")
                          << ") " << r.at("note");
        }
        if (r.at("test") == "equal" && std::stod(r.at("se")) > 0) {
            ++stochastic;
            worst_z = std::max(worst_z, std::fabs(std::stod(r.at("z"))));
        }
    }
    for (const char* e : {"mcml", "pencil", "sphere", "render", "diffusion", "kernel", "SSS"})
        EXPECT_TRUE(engines.count(e)) << e;
    for (const char* a : {"albedo", "g", "eta", "scale", "thickness", "kernel width"})
        EXPECT_TRUE(axes.count(a)) << a;
    EXPECT_GT(rows.size(), 600u);
    EXPECT_GE(stochastic, 90);
    std::printf("  [measured] %zu checks, %d failed, %d z-tests, worst |z| %.2f\n", rows.size(),
                failed, stochastic, worst_z);
}

TEST(StiffSweep, ARunStoppedByTheTimeCapFailsTheSweep) {
    testing::TempDir dir;
    const auto rows = run_sweep(dir, sweep_config("seconds_cap = 1e-9"));
    int stopped = 0;
    for (const auto& r : rows)
        if (r.at("ended") == "0") {
            ++stopped;
            EXPECT_EQ(r.at("pass"), "0");
        }
    // Every Monte Carlo run is stopped after its first batches (the analytic models have no
    // budget).
    EXPECT_GT(stopped, 50);
}

TEST(StiffSweep, BadKeysAreRefusedWithTheirLocation) {
    for (const char* bad : {"seconds_cap = 0", "seconds_cap = -1", "seconds_cap = \"long\"",
                            "seconds_cap = 300\nseconds = 5"}) {
        SCOPED_TRACE(bad);
        try {
            runner::parse_experiment(sweep_config(bad), "sweep.toml");
            ADD_FAILURE() << "accepted";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("sweep.toml:"), std::string::npos) << what;
            EXPECT_NE(what.find("outputs.stiff"), std::string::npos) << what;
        }
    }
}

}  // namespace
}  // namespace ssslab
