// Scale-out over MPI (docs/architecture.md, "Determinism"): every rank runs the same command on the
// same input, so each builds the same simulation; the batch driver (core/batch_runner.cpp) deals
// the batches out over the ranks and folds them on rank 0 in batch order, so a result is
// bit-identical to one process with any thread count. Rank 0 alone touches the outputs: the
// other ranks write nothing (core/atomic_file.cpp), and what a run reads of earlier runs'
// outputs (a checkpoint's fingerprint, an artifact cache entry) is rank 0's, sent to the others.
//
// MPI starts only when the process was launched by mpirun (the launcher's environment says how
// many ranks); a plain `ssslab` never initializes MPI. Built without MPI (SSSLAB_WITH_MPI=OFF),
// a launch by mpirun with more than one rank is refused rather than run N times side by side.
//
// Calls are collective where they say so: every rank must make them in the same order (the
// engines run their batch runs one after the other under MPI).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace ssslab::dist {

/// Starts MPI when launched by mpirun (thread level MPI_THREAD_SERIALIZED: one thread at a time
/// calls MPI, from the batch driver's serial stages), and finalizes it on destruction. Throws
/// InputError when launched with several ranks by a build without MPI.
class Session {
  public:
    Session(int& argc, char**& argv);
    ~Session();
    Session(const Session&) = delete;
    Session& operator=(const Session&) = delete;
};

int rank();
int size();
/// More than one rank.
inline bool active() {
    return size() > 1;
}
/// Rank 0, or the only process: the one that writes outputs and reports.
inline bool is_root() {
    return rank() == 0;
}
/// Whether this build can run under MPI.
bool built_with_mpi();
/// The ranks launched by mpirun according to the launcher's environment (1 without one).
int launched_ranks();

/// End every rank (MPI_Abort) with `status`: after an error on one rank, the others would wait
/// for it forever. A no-op returning normally when not active.
void abort_all(int status);

/// Collective: rank 0's `bytes` on every rank.
void broadcast(std::string& bytes);

/// Collective: rank 0 runs `f` and every rank gets its value (the others do not run it). An
/// exception on rank 0 is rethrown there and, as a std::runtime_error naming rank 0, on the
/// others.
std::optional<std::string> from_root(const std::function<std::optional<std::string>()>& f);

// Point-to-point messages of the batch driver (tags are the driver's).
void send(int dest, int tag, const void* data, std::size_t bytes);
struct Message {
    int source = -1, tag = -1;
    std::string bytes;
};
/// Wait for the next message from any rank (`source` < 0) or one rank, any tag.
Message receive(int source = -1);
/// An empty message that does not wait for its receiver (a signal such as "stop"); sent for
/// sure by complete_notifications().
void notify(int dest, int tag);
void complete_notifications();
/// A message from `source` with `tag` is waiting.
bool poll(int source, int tag);

}  // namespace ssslab::dist
