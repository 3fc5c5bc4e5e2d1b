// Compatibility mode against the original MCML 1.2.2: byte-identical .mco output (after line 10,
// which holds the run time) on the reference cases of tests/data/mcml-1.2.2, made by the original
// program at idum = -24832 (see the README there).
#include "mcml/engine.h"
#include "mcml/mci.h"
#include "mcml/mco.h"
#include "mcml/ran3.h"
#include "testing.h"

#include <gtest/gtest.h>

namespace ssslab::mcml {
namespace {

using testing::data_path;

constexpr int kIdum = -24832;  // -(1577836800 % 32768)

std::string compat_output(const std::string& mci_name) {
    const MciFile f = read_mci(data_path("mcml-1.2.2/" + mci_name), {.allow_negative_g = false});
    EXPECT_EQ(f.runs.size(), 1u);
    Ran3 rng(kIdum);
    const RunSpec& run = f.runs[0];
    const RunResult r = run_compat(run, rng, SampleBudget{});
    return format_mco(run, mco_values(run, r, /*compat=*/true), r.photons, r.seconds);
}

TEST(McmlCompat, VanDeHulstSlabIsByteIdenticalAfterLine10) {
    const std::string ours = compat_output("a_vdh.mci");
    const std::string ref = testing::gunzip_file(data_path("mcml-1.2.2/a_vdh.mco.gz"));
    ASSERT_GT(ref.size(), 1000u);
    EXPECT_EQ(testing::lines_from(ours, 11), testing::lines_from(ref, 11));
    // Lines 1-9 are fixed text too; only line 10 (user time) may differ.
    EXPECT_EQ(ours.substr(0, ours.find("# User time")), ref.substr(0, ref.find("# User time")));
}

TEST(McmlCompat, GiovanelliSemiInfiniteIsByteIdenticalAfterLine10) {
    const std::string ours = compat_output("b_giov_n15.mci");
    const std::string ref = testing::gunzip_file(data_path("mcml-1.2.2/b_giov_n15.mco.gz"));
    ASSERT_GT(ref.size(), 1000u);
    EXPECT_EQ(testing::lines_from(ours, 11), testing::lines_from(ref, 11));
}

TEST(McmlCompat, CommandLineIsADropInReplacement) {
    testing::TempDir dir;
    std::filesystem::copy_file(data_path("mcml-1.2.2/a_vdh.mci"), dir / "a_vdh.mci");
    const auto r = testing::run_ssslab(
        {"mcml", "a_vdh.mci", "--compat", "mcml-1.2.2", "--idum", std::to_string(kIdum)},
        dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string ours = testing::read_text(dir / "a_vdh.mco");
    const std::string ref = testing::gunzip_file(data_path("mcml-1.2.2/a_vdh.mco.gz"));
    EXPECT_EQ(testing::lines_from(ours, 11), testing::lines_from(ref, 11));
    // Standard errors and the resolved run with provenance are written beside the .mco.
    EXPECT_TRUE(std::filesystem::exists(dir / "a_vdh_stderr.mco"));
    const std::string record = testing::read_text(dir / "a_vdh.mco.toml");
    EXPECT_NE(record.find("idum = -24832"), std::string::npos) << record;
    EXPECT_NE(record.find("git_revision"), std::string::npos);
}

TEST(McmlCompat, StateOfTheGeneratorCarriesAcrossRunsOfOneFile) {
    // The original seeds ran3 once per process: run 2 of a file continues run 1's sequence.
    const MciFile f = read_mci(data_path("mcml-1.2.2/a_vdh.mci"));
    RunSpec small = f.runs[0];
    small.photons = 1000;
    Ran3 shared(kIdum);
    (void)run_compat(small, shared, SampleBudget{});
    const RunResult second = run_compat(small, shared, SampleBudget{});
    Ran3 fresh(kIdum);
    const RunResult first = run_compat(small, fresh, SampleBudget{});
    EXPECT_NE(first.values, second.values);
}

}  // namespace
}  // namespace ssslab::mcml
