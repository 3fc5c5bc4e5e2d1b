// The artifact cache: results/cache/<kind>/<key>/ holds one finished artifact (its files and a
// manifest). An entry appears atomically: it is written into a temporary directory beside it and
// renamed, so an interrupted run never leaves a half-written entry; checkpoints of unfinished
// artifacts live beside the entries as <key>.ckpt* and are removed when the artifact is done.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>

namespace ssslab::runner {

class ArtifactCache {
  public:
    explicit ArtifactCache(std::filesystem::path root) : root_(std::move(root)) {}

    const std::filesystem::path& root() const { return root_; }
    /// Directory of a finished entry, if present. Collective under MPI (core/distributed.h):
    /// rank 0's cache decides, and the other ranks (each with a cache of its own) receive the
    /// entry's files from it, so that every rank computes what rank 0 computes.
    std::optional<std::filesystem::path> find(const std::string& kind,
                                              const std::string& key) const;
    /// This process's entry only (not collective).
    std::optional<std::filesystem::path> find_here(const std::string& kind,
                                                   const std::string& key) const;
    /// Store an entry of named files atomically; returns its directory. If another run stored it
    /// meanwhile, that entry is kept (it has the same content by construction).
    std::filesystem::path store(const std::string& kind, const std::string& key,
                                const std::map<std::string, std::string>& files) const;
    /// Path prefix for the checkpoints of an unfinished entry.
    std::filesystem::path checkpoint_prefix(const std::string& kind, const std::string& key) const;
    /// Remove what runs that were killed left: temporary directories (their process gone) and
    /// checkpoints of entries that were stored.
    void remove_stale_temporaries() const;

  private:
    std::filesystem::path root_;
};

}  // namespace ssslab::runner
