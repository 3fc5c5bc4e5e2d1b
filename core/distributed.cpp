#include "core/distributed.h"

#include "core/error.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <vector>

#ifdef SSSLAB_HAVE_MPI
#include <mpi.h>
#endif

namespace ssslab::dist {

namespace {

int g_rank = 0;
int g_size = 1;
bool g_started = false;

int env_int(const char* name) {
    const char* v = std::getenv(name);
    if (!v || !*v) return 0;
    char* end = nullptr;
    const long n = std::strtol(v, &end, 10);
    return end && *end == '\0' && n > 0 && n < (1L << 30) ? static_cast<int>(n) : 0;
}

#ifdef SSSLAB_HAVE_MPI
void check(int rc, const char* what) {
    if (rc != MPI_SUCCESS) {
        char text[MPI_MAX_ERROR_STRING];
        int len = 0;
        MPI_Error_string(rc, text, &len);
        throw std::runtime_error(std::string("MPI: ") + what +
                                 " failed: " + std::string(text, len));
    }
}
#endif

}  // namespace

int launched_ranks() {
    // Open MPI's mpirun, then the PMI variables of MPICH / Slurm launchers.
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "SLURM_NTASKS"})
        if (const int n = env_int(v)) return n;
    return 1;
}

bool built_with_mpi() {
#ifdef SSSLAB_HAVE_MPI
    return true;
#else
    return false;
#endif
}

Session::Session([[maybe_unused]] int& argc, [[maybe_unused]] char**& argv) {
    const int launched = launched_ranks();
    if (launched <= 1 || std::getenv("SSSLAB_NO_MPI")) return;
#ifdef SSSLAB_HAVE_MPI
    int provided = 0;
    check(MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided), "MPI_Init_thread");
    g_started = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &g_size);
    if (provided < MPI_THREAD_SERIALIZED) {
        if (g_rank == 0)
            std::fprintf(stderr,
                         "error: this MPI library does not allow calls from several threads "
                         "(MPI_THREAD_SERIALIZED)\n");
        MPI_Abort(MPI_COMM_WORLD, 2);
    }
#else
    throw InputError({}, "",
                     "launched by mpirun with " + std::to_string(launched) +
                         " ranks, but this ssslab was built without MPI: rebuild with "
                         "-DSSSLAB_WITH_MPI=ON (apt-get install libopenmpi-dev), or run one "
                         "process (SSSLAB_NO_MPI=1 runs each rank alone)");
#endif
}

Session::~Session() {
#ifdef SSSLAB_HAVE_MPI
    if (g_started) MPI_Finalize();
#endif
    g_started = false;
    g_rank = 0;
    g_size = 1;
}

int rank() {
    return g_rank;
}

int size() {
    return g_size;
}

void abort_all([[maybe_unused]] int status) {
#ifdef SSSLAB_HAVE_MPI
    if (g_started && g_size > 1) MPI_Abort(MPI_COMM_WORLD, status);
#endif
}

void broadcast([[maybe_unused]] std::string& bytes) {
#ifdef SSSLAB_HAVE_MPI
    if (!active()) return;
    unsigned long long n = bytes.size();
    check(MPI_Bcast(&n, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD), "MPI_Bcast");
    bytes.resize(n);
    // In pieces below INT_MAX bytes (MPI counts are int).
    const std::size_t piece = std::size_t(1) << 30;
    for (std::size_t at = 0; at < n; at += piece) {
        const int count = static_cast<int>(std::min<std::size_t>(piece, n - at));
        check(MPI_Bcast(bytes.data() + at, count, MPI_BYTE, 0, MPI_COMM_WORLD), "MPI_Bcast");
    }
#endif
}

std::optional<std::string> from_root(const std::function<std::optional<std::string>()>& f) {
    if (!active()) return f();
    // One message: a status byte ('-' none, '+' a value, '!' an error) and the value or message.
    std::string msg;
    std::exception_ptr error;
    if (is_root()) {
        try {
            const auto v = f();
            msg = v ? "+" + *v : "-";
        } catch (const std::exception& e) {
            error = std::current_exception();
            msg = std::string("!") + e.what();
        }
    }
    broadcast(msg);
    if (error) std::rethrow_exception(error);
    if (msg.empty()) throw std::runtime_error("MPI: an empty message from rank 0");
    if (msg[0] == '!') throw std::runtime_error("on rank 0: " + msg.substr(1));
    if (msg[0] == '-') return std::nullopt;
    return msg.substr(1);
}

void send([[maybe_unused]] int dest, [[maybe_unused]] int tag, [[maybe_unused]] const void* data,
          [[maybe_unused]] std::size_t bytes) {
#ifdef SSSLAB_HAVE_MPI
    if (bytes > static_cast<std::size_t>(std::numeric_limits<int>::max()))
        throw std::runtime_error("MPI: a message of more than 2 GiB");
    check(MPI_Send(data, static_cast<int>(bytes), MPI_BYTE, dest, tag, MPI_COMM_WORLD), "MPI_Send");
#else
    throw std::logic_error("dist::send without MPI");
#endif
}

Message receive([[maybe_unused]] int source) {
    Message m;
#ifdef SSSLAB_HAVE_MPI
    MPI_Status st;
    check(MPI_Probe(source < 0 ? MPI_ANY_SOURCE : source, MPI_ANY_TAG, MPI_COMM_WORLD, &st),
          "MPI_Probe");
    int count = 0;
    MPI_Get_count(&st, MPI_BYTE, &count);
    m.source = st.MPI_SOURCE;
    m.tag = st.MPI_TAG;
    m.bytes.resize(static_cast<std::size_t>(count));
    check(MPI_Recv(m.bytes.data(), count, MPI_BYTE, m.source, m.tag, MPI_COMM_WORLD,
                   MPI_STATUS_IGNORE),
          "MPI_Recv");
#else
    throw std::logic_error("dist::receive without MPI");
#endif
    return m;
}

namespace {
#ifdef SSSLAB_HAVE_MPI
std::vector<MPI_Request> g_notes;
#endif
}  // namespace

void notify([[maybe_unused]] int dest, [[maybe_unused]] int tag) {
#ifdef SSSLAB_HAVE_MPI
    g_notes.emplace_back();
    check(MPI_Isend(nullptr, 0, MPI_BYTE, dest, tag, MPI_COMM_WORLD, &g_notes.back()), "MPI_Isend");
#endif
}

void complete_notifications() {
#ifdef SSSLAB_HAVE_MPI
    if (g_notes.empty()) return;
    check(MPI_Waitall(static_cast<int>(g_notes.size()), g_notes.data(), MPI_STATUSES_IGNORE),
          "MPI_Waitall");
    g_notes.clear();
#endif
}

bool poll([[maybe_unused]] int source, [[maybe_unused]] int tag) {
#ifdef SSSLAB_HAVE_MPI
    int flag = 0;
    check(MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE), "MPI_Iprobe");
    return flag != 0;
#else
    return false;
#endif
}

}  // namespace ssslab::dist
