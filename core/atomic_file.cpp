#include "core/atomic_file.h"

#include "core/crash_point.h"
#include "core/error.h"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

namespace ssslab {

namespace fs = std::filesystem;

namespace {

std::atomic<bool> g_discard{false};

const std::string kTempMark = ".tmp.";

fs::path temp_name(const fs::path& path) {
    return fs::path(path.string() + kTempMark + std::to_string(::getpid()));
}

// Temporaries of `path` left by killed writers (<name>.tmp.<pid> of a pid no longer alive):
// removed before the next write of the same file, so a kill leaves no litter for long.
void remove_orphaned_temporaries(const fs::path& path) {
    const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    const std::string prefix = path.filename().string() + kTempMark;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        const std::string n = e.path().filename().string();
        if (n.size() > prefix.size() && n.compare(0, prefix.size(), prefix) == 0 &&
            owner_is_gone(e.path()))
            fs::remove(e.path(), ec);
    }
}

void write_temp(const fs::path& tmp, std::string_view content) {
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw IoError("cannot create '" + tmp.string() + "': " + std::strerror(errno));
    size_t done = 0;
    while (done < content.size()) {
        // Half of it first, so that a kill test can die with a partly written temporary.
        const size_t chunk =
            done == 0 && content.size() > 1 ? content.size() / 2 : content.size() - done;
        const ssize_t n = ::write(fd, content.data() + done, chunk);
        if (n < 0) {
            if (errno == EINTR) continue;
            const std::string err = std::strerror(errno);
            ::close(fd);
            ::unlink(tmp.c_str());
            throw IoError("cannot write '" + tmp.string() + "': " + err);
        }
        done += static_cast<size_t>(n);
        if (done < content.size()) crash_point("write.partial");
    }
    // Data must be on disk before the rename makes it visible under the final name.
    if (::fsync(fd) != 0 || ::close(fd) != 0) {
        const std::string err = std::strerror(errno);
        ::unlink(tmp.c_str());
        throw IoError("cannot write '" + tmp.string() + "': " + err);
    }
    crash_point("write.temporary");
}

void make_parent(const fs::path& path) {
    const fs::path parent = path.parent_path();
    if (parent.empty()) return;
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) throw IoError("cannot create directory '" + parent.string() + "': " + ec.message());
}

}  // namespace

bool owner_is_gone(const fs::path& temporary) {
    const std::string n = temporary.filename().string();
    size_t i = n.size();
    while (i > 0 && n[i - 1] >= '0' && n[i - 1] <= '9') --i;
    if (i == n.size() || n.size() - i > 9) return false;
    const long pid = std::stol(n.substr(i));
    if (pid <= 0 || pid == static_cast<long>(::getpid())) return false;
    return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

void discard_outputs(bool discard) {
    g_discard = discard;
}

bool outputs_discarded() {
    return g_discard;
}

void write_file_atomic(const fs::path& path, std::string_view content) {
    if (g_discard) return;
    make_parent(path);
    remove_orphaned_temporaries(path);
    const fs::path tmp = temp_name(path);
    write_temp(tmp, content);
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        const std::string err = std::strerror(errno);
        ::unlink(tmp.c_str());
        throw IoError("cannot rename '" + tmp.string() + "' to '" + path.string() + "': " + err);
    }
    crash_point("write.renamed");
}

OutputTransaction::~OutputTransaction() {
    if (committed_) return;
    for (const auto& t : temps_) ::unlink(t.c_str());
}

void OutputTransaction::stage(const fs::path& path, std::string_view content) {
    if (g_discard) {
        finals_.push_back(path);
        return;
    }
    make_parent(path);
    remove_orphaned_temporaries(path);
    const fs::path tmp = temp_name(path);
    write_temp(tmp, content);
    temps_.push_back(tmp);
    finals_.push_back(path);
}

void OutputTransaction::commit() {
    for (size_t i = 0; i < temps_.size(); ++i) {
        if (std::rename(temps_[i].c_str(), finals_[i].c_str()) != 0)
            throw IoError("cannot rename '" + temps_[i].string() + "' to '" + finals_[i].string() +
                          "': " + std::strerror(errno));
        crash_point("transaction.renamed");
    }
    committed_ = true;
}

std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError("cannot open '" + path.string() + "' for reading");
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::string read_input_file(const fs::path& path, const std::string& what) {
    try {
        return read_file(path);
    } catch (const IoError&) {
        throw InputError({path.string(), 0, 0}, "", "cannot read the " + what);
    }
}

}  // namespace ssslab
