// Strict, typed access to TOML configuration files (toml++ keeps source positions).
//
// Every value is read through a ConfigTable getter that knows its type, range and default; every
// key that no getter asked for is an error at finish() (pbrt's ParameterDictionary::ReportUnused,
// Nori's strict parser). Errors name file:line:column, the key and what was expected, and show the
// offending line with a caret (Tungsten). Each getter also records the value it resolved, so that
// the fully resolved configuration, defaults filled in, can be written next to every output.
#pragma once

#include "core/vec3.h"

#include "core/enum_names.h"
#include "core/error.h"

#include <array>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace toml {
inline namespace v3 {
class table;
class node;
}  // namespace v3
}  // namespace toml

namespace ssslab {

/// An interval of admissible values for a number; bounds may be open or infinite.
struct Range {
    double lo = -1e308 * 10, hi = 1e308 * 10;  // -inf, +inf
    bool lo_open = true, hi_open = true;

    static Range any() { return {}; }
    static Range closed(double a, double b) { return {a, b, false, false}; }
    static Range open(double a, double b) { return {a, b, true, true}; }
    static Range left_open(double a, double b) { return {a, b, true, false}; }
    static Range right_open(double a, double b) { return {a, b, false, true}; }
    static Range positive() { return {0.0, Range{}.hi, true, true}; }
    static Range nonnegative() { return {0.0, Range{}.hi, false, true}; }
    static Range at_least(double a) { return {a, Range{}.hi, false, true}; }

    bool contains(double v) const;
    std::string describe() const;  ///< e.g. "(0, inf)" or "[-1, 1]"
};

class ConfigDocument;

/// A table of a parsed configuration (the root or a sub-table).
class ConfigTable {
  public:
    /// Whether the key is present (does not mark it as used).
    bool has(std::string_view key) const;

    // Optional values with a default, and required values. Numbers accept TOML integers and
    // floats; integers accept floats that are whole numbers (so `photons = 1e7` works).
    double number(std::string_view key, double fallback, Range range = Range::any());
    double number(std::string_view key, Range range = Range::any());
    std::int64_t integer(std::string_view key, std::int64_t fallback, Range range = Range::any());
    std::int64_t integer(std::string_view key, Range range = Range::any());
    bool boolean(std::string_view key, bool fallback);
    std::string string(std::string_view key, std::string fallback);
    std::string string(std::string_view key);
    /// A string from a fixed set of choices (the error lists them).
    std::string choice(std::string_view key, std::string fallback,
                       std::initializer_list<std::string_view> choices);
    std::string choice(std::string_view key, std::string fallback,
                       const std::vector<std::string>& choices);
    /// An enum value by its spelling (core/enum_names.h); the resolved config records the
    /// spelling of the value taken, fallback included.
    template <class E>
    E enumerated(std::string_view key, E fallback) {
        return *parse_name<E>(choice(key, std::string(name_of(fallback)), names_of<E>()));
    }
    /// A required array of strings (may be empty).
    std::vector<std::string> string_list(std::string_view key);
    /// An optional array of strings (the key is known to "did you mean" even when absent).
    std::optional<std::vector<std::string>> optional_string_list(std::string_view key);
    /// An optional array of numbers, each in `range` (a bad item is located at itself).
    std::optional<std::vector<double>> optional_number_list(std::string_view key,
                                                            Range range = Range::any());
    /// An optional string.
    std::optional<std::string> optional_string(std::string_view key);
    std::optional<double> optional_number(std::string_view key, Range range = Range::any());
    std::optional<std::int64_t> optional_integer(std::string_view key, Range range = Range::any());
    /// Three numbers per RGB channel: an array of three, or one number used for all three.
    std::array<double, 3> rgb(std::string_view key, Range range = Range::any());
    std::optional<std::array<double, 3>> optional_rgb(std::string_view key,
                                                      Range range = Range::any());

    /// A point or direction: exactly three numbers [x, y, z], each in `range`.
    Vec3 vec3(std::string_view key, Range range = Range::any());
    std::optional<Vec3> optional_vec3(std::string_view key, Range range = Range::any());

    /// A sub-table, if present (marks the key as used).
    std::optional<ConfigTable> table(std::string_view key);
    ConfigTable require_table(std::string_view key);
    /// A sub-table, or an empty one reading as all defaults when absent.
    ConfigTable table_or_empty(std::string_view key);
    /// An array of tables ([[key]] in TOML); empty when absent.
    std::vector<ConfigTable> table_array(std::string_view key);

    /// Throws an InputError for the first key, in this table or any sub-table that was asked
    /// for, that no getter asked for; with a "did you mean" suggestion among the keys that were.
    void finish() const;

    /// Throws an InputError located at `key` (or at the table when the key is absent).
    [[noreturn]] void fail(std::string_view key, const std::string& message) const;
    /// Throws an InputError located at item `index` of the array `key` (at the key itself when
    /// it is not an array that long, e.g. one number given for all three channels).
    [[noreturn]] void fail_item(std::string_view key, std::size_t index,
                                const std::string& message) const;
    SourceLocation location(std::string_view key) const;

    /// Dotted path of this table ("" for the root).
    const std::string& path() const { return path_; }
    /// Dotted path of a key of this table.
    std::string key_path(std::string_view key) const;

    /// Record a resolved value that did not come from a getter (e.g. a derived default).
    void record(std::string_view key, double value);
    void record(std::string_view key, std::int64_t value);
    void record(std::string_view key, const std::string& value);
    /// ... an array of numbers (an RGB triple), or of such arrays (one per layer).
    void record(std::string_view key, const std::vector<double>& values);
    void record(std::string_view key, const std::vector<std::vector<double>>& rows);

  private:
    friend class ConfigDocument;
    ConfigTable(std::shared_ptr<ConfigDocument> doc, const toml::table* table,
                toml::table* resolved, std::string path);
    const toml::node* find(std::string_view key) const;
    double to_number(std::string_view key, const toml::node& n, Range range) const;
    [[noreturn]] void fail_at(const toml::node* n, std::string_view key,
                              const std::string& message) const;

    void mark(std::string_view key) const;

    std::shared_ptr<ConfigDocument> doc_;
    const toml::table* table_;  // may be null: an absent table reads as all defaults
    toml::table* resolved_;
    std::string path_;
};

/// A parsed TOML file (or string) and its resolved counterpart.
class ConfigDocument : public std::enable_shared_from_this<ConfigDocument> {
  public:
    /// Parse a file; syntax errors are InputErrors with file:line:column.
    static std::shared_ptr<ConfigDocument> parse_file(const std::string& path);
    /// Parse text; `name` is used as the file name in messages.
    static std::shared_ptr<ConfigDocument> parse_string(std::string_view text,
                                                        const std::string& name);
    /// An empty document (all defaults), named `name` in messages.
    static std::shared_ptr<ConfigDocument> empty(const std::string& name);
    ~ConfigDocument();

    ConfigTable root();
    const std::string& name() const { return name_; }
    std::string source_line(int line) const;

    /// The resolved configuration as TOML text (all values that getters returned, defaults
    /// included, in the order they were asked for).
    std::string resolved_toml() const;
    /// Insert a table of extra information (e.g. provenance) into the resolved configuration.
    void add_resolved_section(const std::string& name,
                              const std::vector<std::pair<std::string, std::string>>& entries);

  private:
    friend class ConfigTable;
    ConfigDocument();
    std::string name_;
    std::map<std::string, std::set<std::string>> used_;      // table path -> keys marked used
    std::map<std::string, std::vector<std::string>> asked_;  // table path -> keys asked for
    std::vector<std::string> lines_;
    std::unique_ptr<toml::table> table_;
    std::unique_ptr<toml::table> resolved_;
};

}  // namespace ssslab
