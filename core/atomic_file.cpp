#include "core/atomic_file.h"

#include "core/error.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

namespace ssslab {

namespace fs = std::filesystem;

namespace {

fs::path temp_name(const fs::path& path) {
    return fs::path(path.string() + ".tmp." + std::to_string(::getpid()));
}

void write_temp(const fs::path& tmp, std::string_view content) {
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw IoError("cannot create '" + tmp.string() + "': " + std::strerror(errno));
    size_t done = 0;
    while (done < content.size()) {
        const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            const std::string err = std::strerror(errno);
            ::close(fd);
            ::unlink(tmp.c_str());
            throw IoError("cannot write '" + tmp.string() + "': " + err);
        }
        done += static_cast<size_t>(n);
    }
    // Data must be on disk before the rename makes it visible under the final name.
    if (::fsync(fd) != 0 || ::close(fd) != 0) {
        const std::string err = std::strerror(errno);
        ::unlink(tmp.c_str());
        throw IoError("cannot write '" + tmp.string() + "': " + err);
    }
}

void make_parent(const fs::path& path) {
    const fs::path parent = path.parent_path();
    if (parent.empty()) return;
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) throw IoError("cannot create directory '" + parent.string() + "': " + ec.message());
}

}  // namespace

void write_file_atomic(const fs::path& path, std::string_view content) {
    make_parent(path);
    const fs::path tmp = temp_name(path);
    write_temp(tmp, content);
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        const std::string err = std::strerror(errno);
        ::unlink(tmp.c_str());
        throw IoError("cannot rename '" + tmp.string() + "' to '" + path.string() + "': " + err);
    }
}

OutputTransaction::~OutputTransaction() {
    if (committed_) return;
    for (const auto& t : temps_) ::unlink(t.c_str());
}

void OutputTransaction::stage(const fs::path& path, std::string_view content) {
    make_parent(path);
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

}  // namespace ssslab
