// Typed errors. Library code throws; only the command line catches, prints and exits
// (as OpenVDB: "library code must never deliberately terminate the application").
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace ssslab {

/// Where in an input file something was found. line and column count from 1; 0 means unknown.
struct SourceLocation {
    std::string file;
    int line = 0;
    int column = 0;
};

/// Bad user input: a config, a scene, an .mci file, a command-line value. The message names the
/// file, line and column, the key, what was expected, and shows the offending line with a caret.
class InputError : public std::runtime_error {
  public:
    /// `key` may be empty (e.g. a syntax error); `line_text` is the offending line, if known.
    InputError(SourceLocation where, std::string key, std::string message,
               std::string line_text = {});

    const SourceLocation& where() const { return where_; }
    const std::string& key() const { return key_; }
    /// The message without location and caret.
    const std::string& message() const { return message_; }

  private:
    SourceLocation where_;
    std::string key_;
    std::string message_;
};

/// An input that is well-formed but describes a computation that cannot finish in bounded
/// expected time or memory (e.g. mu_a = 0 in a semi-infinite medium). Refused before work starts.
class InfeasibleError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Failure of the environment: a file that cannot be written, a full disk.
class IoError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Read line `line` (from 1) of a file, without its line terminator; empty if unavailable.
std::string read_source_line(const std::string& file, int line);

/// Levenshtein distance, for "did you mean" suggestions.
int edit_distance(const std::string& a, const std::string& b);

/// The candidate nearest to `name` by edit_distance (the first of equally near ones) if it is
/// at most `max_distance` edits away, else "": the one "did you mean" lookup.
std::string nearest_name(const std::string& name, const std::vector<std::string>& candidates,
                         int max_distance);
/// How far a suggestion for a name may be: 2 edits, or a third of a longer name's length.
int suggestion_distance(const std::string& name);

}  // namespace ssslab
