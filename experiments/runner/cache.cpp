#include "experiments/runner/cache.h"

#include "core/atomic_file.h"
#include "core/batch_runner.h"
#include "core/crash_point.h"
#include "core/distributed.h"
#include "core/error.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <unistd.h>

namespace ssslab::runner {

namespace fs = std::filesystem;

std::optional<fs::path> ArtifactCache::find_here(const std::string& kind,
                                                 const std::string& key) const {
    const fs::path dir = root_ / kind / key;
    std::error_code ec;
    if (fs::exists(dir / "manifest.toml", ec)) return dir;
    return std::nullopt;
}

namespace {

// An entry's files as one message: (name length, name, content length, content) per file.
std::string pack_entry(const fs::path& dir) {
    std::string out;
    auto put = [&](const std::string& s) {
        const std::uint64_t n = s.size();
        out.append(reinterpret_cast<const char*>(&n), sizeof n);
        out += s;
    };
    for (const auto& e : fs::directory_iterator(dir))
        if (e.is_regular_file()) {
            put(e.path().filename().string());
            put(read_file(e.path()));
        }
    return out;
}

std::map<std::string, std::string> unpack_entry(const std::string& bytes) {
    std::map<std::string, std::string> files;
    size_t at = 0;
    auto get = [&] {
        std::uint64_t n = 0;
        if (at + sizeof n > bytes.size()) throw std::runtime_error("MPI: a truncated cache entry");
        std::memcpy(&n, bytes.data() + at, sizeof n);
        at += sizeof n;
        if (n > bytes.size() - at) throw std::runtime_error("MPI: a truncated cache entry");
        std::string s = bytes.substr(at, n);
        at += n;
        return s;
    };
    while (at < bytes.size()) {
        std::string name = get();
        files[name] = get();
    }
    return files;
}

}  // namespace

std::optional<fs::path> ArtifactCache::find(const std::string& kind, const std::string& key) const {
    if (!dist::active()) return find_here(kind, key);
    std::optional<fs::path> here;  // rank 0's entry
    const auto entry = dist::from_root([&]() -> std::optional<std::string> {
        here = find_here(kind, key);
        if (here) return pack_entry(*here);
        return std::nullopt;
    });
    if (dist::is_root()) return here;
    if (!entry) return std::nullopt;
    if (const auto dir = find_here(kind, key)) return dir;
    return store(kind, key, unpack_entry(*entry));
}

fs::path ArtifactCache::checkpoint_prefix(const std::string& kind, const std::string& key) const {
    std::error_code ec;
    fs::create_directories(root_ / kind, ec);
    return root_ / kind / (key + ".ckpt");
}

fs::path ArtifactCache::store(const std::string& kind, const std::string& key,
                              const std::map<std::string, std::string>& files) const {
    const fs::path final_dir = root_ / kind / key;
    const fs::path tmp = root_ / kind / (".tmp-" + key + "-" + std::to_string(::getpid()));
    std::error_code ec;
    fs::remove_all(tmp, ec);
    fs::create_directories(tmp, ec);
    if (ec) throw IoError("cannot create '" + tmp.string() + "': " + ec.message());
    for (const auto& [name, content] : files) write_file_atomic(tmp / name, content);
    crash_point("cache.staged");
    if (std::rename(tmp.c_str(), final_dir.c_str()) != 0) {
        const int err = errno;
        fs::remove_all(tmp, ec);
        if (!((err == ENOTEMPTY || err == EEXIST) && fs::exists(final_dir / "manifest.toml", ec)))
            throw IoError("cannot rename '" + tmp.string() + "' to '" + final_dir.string() +
                          "': " + std::strerror(err));
    }
    crash_point("cache.stored");
    // The engines keep their checkpoints until the result is stored (core/batch_runner.h):
    // checkpoint_prefix(kind, key) = <key>.ckpt, and the runs' files under that prefix.
    const std::string prefix = (root_ / kind / key).string();
    remove_checkpoints(prefix);
    remove_checkpoints(prefix + ".ckpt");
    return final_dir;
}

void ArtifactCache::remove_stale_temporaries() const {
    std::error_code ec;
    if (!fs::exists(root_, ec)) return;
    for (const auto& kind : fs::directory_iterator(root_, ec)) {
        if (!kind.is_directory()) continue;
        for (const auto& e : fs::directory_iterator(kind.path(), ec)) {
            const std::string n = e.path().filename().string();
            if (n.rfind(".tmp-", 0) == 0) {
                if (owner_is_gone(e.path())) fs::remove_all(e.path(), ec);
                continue;
            }
            // A checkpoint of an entry that is stored: its run was killed after the store and
            // before it removed the checkpoint.
            const size_t ck = n.find(".ckpt");
            if (ck != std::string::npos && ck > 0 &&
                fs::exists(kind.path() / n.substr(0, ck) / "manifest.toml", ec))
                fs::remove(e.path(), ec);
        }
    }
}

}  // namespace ssslab::runner
