// Scale-out over MPI (issue 17; core/distributed.h). Each command of the process-level cases
// (tests/command_cases.h: `ssslab mcml`, `profile`, `render`, `sphere`, `run`) launched by mpirun
// on 2 and 3 ranks ends with the outputs of one process with two threads bit for bit (the cache's
// channel runs to the last bit of every estimate); a distributed run killed after a checkpoint
// resumes on another number of ranks to the same outputs; bad input under mpirun exits 2 with
// rank 0's message once. Skipped where this build has no MPI or mpirun is missing (CI has both).
#include "command_cases.h"
#include "testing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

namespace ssslab {
namespace {

using testing::CommandCase;

/// The case's args with --threads set to `threads`.
std::vector<std::string> threads(std::vector<std::string> args, int n) {
    return testing::with(std::move(args), "--threads", std::to_string(n));
}

TEST(Mpi, EveryCommandOnTwoAndThreeRanksEqualsOneProcessBitForBit) {
    if (testing::mpi_launcher(2).empty()) GTEST_SKIP() << "no MPI in this build or no mpirun";
    for (const CommandCase& c : testing::command_cases()) {
        SCOPED_TRACE(c.name);
        testing::TempDir one;
        testing::write_inputs(c, one);
        const auto r = testing::run_ssslab(c.args, one.path());
        ASSERT_EQ(r.exit_code, 0) << r.err;
        for (const auto& [ranks, per_rank] : {std::pair{2, 1}, std::pair{3, 2}}) {
            const std::string when =
                std::to_string(ranks) + " ranks of " + std::to_string(per_rank) + " threads";
            testing::TempDir dir;
            testing::write_inputs(c, dir);
            const auto m = testing::run_ssslab(threads(c.args, per_rank), dir.path(),
                                               testing::mpi_launcher(ranks));
            ASSERT_EQ(m.exit_code, 0) << when << "\n" << m.err;
            testing::expect_finished(c, dir.path(), one.path(), when);
        }
    }
}

TEST(Mpi, ADistributedRunKilledAfterACheckpointResumesOnOtherRanksToTheSameResult) {
    if (testing::mpi_launcher(2).empty()) GTEST_SKIP() << "no MPI in this build or no mpirun";
    for (const CommandCase& c : testing::command_cases()) {
        // One case of each kind of output: MCML's tables, a path-traced image, an experiment.
        if (c.name != "mcml" && c.name != "render" && c.name != "run") continue;
        SCOPED_TRACE(c.name);
        testing::TempDir whole;
        testing::write_inputs(c, whole);
        const auto r = testing::run_ssslab(c.long_args, whole.path());
        ASSERT_EQ(r.exit_code, 0) << r.err;

        testing::TempDir dir;
        testing::write_inputs(c, dir);
        // Checkpoints every 20 ms; rank 0 dies by SIGKILL when its second one is in place (the
        // 6th point: half written, written, renamed, twice), and mpirun ends the other rank.
        ::setenv("SSSLAB_CHECKPOINT_SECONDS", "0.02", 1);
        ::setenv("SSSLAB_CRASH_AT", "6", 1);
        const auto killed =
            testing::run_ssslab(threads(c.long_args, 1), dir.path(), testing::mpi_launcher(2));
        ::unsetenv("SSSLAB_CRASH_AT");
        EXPECT_NE(killed.exit_code, 0) << "the run was not killed";
        testing::expect_nothing_partial(c, dir.path(), whole.path(), "killed on 2 ranks");
        bool checkpointed = false;
        for (const std::string& rel : testing::tree(dir.path()))
            checkpointed |= rel.find(".ckpt") != std::string::npos;
        EXPECT_TRUE(checkpointed) << "the killed run left no checkpoint to resume from";

        const auto again =
            testing::run_ssslab(threads(c.long_args, 1), dir.path(), testing::mpi_launcher(3));
        ::unsetenv("SSSLAB_CHECKPOINT_SECONDS");
        ASSERT_EQ(again.exit_code, 0) << again.err;
        testing::expect_finished(c, dir.path(), whole.path(), "resumed on 3 ranks");
    }
}

TEST(Mpi, BadInputUnderMpirunExits2WithOneMessage) {
    if (testing::mpi_launcher(2).empty()) GTEST_SKIP() << "no MPI in this build or no mpirun";
    testing::TempDir dir;
    dir.write("bad.mci", "1.0\nA\n1\n100\n");
    const auto r =
        testing::run_ssslab({"mcml", "bad.mci", "-q"}, dir.path(), testing::mpi_launcher(2));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const std::string marker = "bad.mci:";
    size_t count = 0;
    for (size_t at = r.err.find(marker); at != std::string::npos; at = r.err.find(marker, at + 1))
        ++count;
    EXPECT_EQ(count, 1u) << r.err;
    EXPECT_EQ(testing::tree(dir.path()).size(), 1u) << "bad input left an output";
}

}  // namespace
}  // namespace ssslab
