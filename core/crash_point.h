// Fault injection for the kill tests (issue 17): a named point on the way to an output (a
// temporary written half, written whole, renamed; a staged cache entry; a results directory
// swapped in) where a test can have the process die by SIGKILL, as a machine or a user might
// kill it there. Without the environment variables below a crash point costs one relaxed load.
//
//   SSSLAB_CRASH_AT=N     the N-th crash point this process passes (counting from 1, across
//                         threads) raises SIGKILL instead of returning
//   SSSLAB_CRASH_LOG=FILE each point passed appends "<n> <name>\n" to FILE (one write(2) each,
//                         so the log is complete up to the point of death)
//
// tests/test_kill.cpp kills a command at every point in turn and checks that what is left is
// resumable and never a partial output.
#pragma once

namespace ssslab {

/// Pass the crash point `name` (a string literal): dies here if SSSLAB_CRASH_AT says so.
void crash_point(const char* name);

}  // namespace ssslab
