// Results are written atomically: to a temporary name in the target directory, then renamed, so
// that a reader (or a rerun after a kill) never sees a half-written file (docs/architecture.md,
// "Bad input").
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace ssslab {

/// Write `content` to `path` through a temporary file (<path>.tmp.<pid>) and an atomic rename.
/// Creates the parent directory if needed; removes temporaries of `path` left by killed
/// processes. Throws IoError.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

/// From now on, write nothing: write_file_atomic, OutputTransaction and remove_checkpoints
/// return as if done. The ranks other than 0 of an MPI run (core/distributed.h) compute what
/// rank 0 computes and discard it; rank 0 writes.
void discard_outputs(bool discard);
bool outputs_discarded();

/// Whether the process that made `temporary` (a name ending in its pid: <file>.tmp.<pid>,
/// <dir>.tmp-<pid>, <dir>.old-<pid>) is gone from this machine, so the temporary is litter of a
/// killed run. False for the calling process's own and for names without a pid.
bool owner_is_gone(const std::filesystem::path& temporary);

/// Several files that appear together or not at all: each is staged under a temporary name and
/// all are renamed by commit(). If the transaction is destroyed without commit() (an exception,
/// an error found late), the staged files are removed and no output is left behind. A SIGKILL
/// between two of commit()'s renames (no process can rename several files as one) leaves the
/// first files complete and the rest absent (or as they were): the commands remove their
/// checkpoint only after commit(), so running the same command again writes the whole set
/// (tests/test_kill.cpp).
class OutputTransaction {
  public:
    OutputTransaction() = default;
    OutputTransaction(const OutputTransaction&) = delete;
    OutputTransaction& operator=(const OutputTransaction&) = delete;
    ~OutputTransaction();

    void stage(const std::filesystem::path& path, std::string_view content);
    /// Rename every staged file to its final name.
    void commit();
    const std::vector<std::filesystem::path>& paths() const { return finals_; }

  private:
    std::vector<std::filesystem::path> temps_;
    std::vector<std::filesystem::path> finals_;
    bool committed_ = false;
};

/// Read a whole file (binary). Throws IoError.
std::string read_file(const std::filesystem::path& path);
/// Read a whole input file the user named: an InputError located at the file ("cannot read
/// the <what>") when it cannot be read, so that the command exits 2 naming it.
std::string read_input_file(const std::filesystem::path& path, const std::string& what);

}  // namespace ssslab
