#include "core/config.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace ssslab {

// ---------------------------------------------------------------------------------------------
// Range

bool Range::contains(double v) const {
    if (!std::isfinite(v)) return false;
    if (lo_open ? !(v > lo) : !(v >= lo)) return false;
    if (hi_open ? !(v < hi) : !(v <= hi)) return false;
    return true;
}

std::string Range::describe() const {
    auto num = [](double x) {
        if (std::isinf(x)) return std::string(x < 0 ? "-inf" : "inf");
        std::ostringstream os;
        os << x;
        return os.str();
    };
    return std::string(lo_open ? "(" : "[") + num(lo) + ", " + num(hi) + (hi_open ? ")" : "]");
}

// ---------------------------------------------------------------------------------------------
// ConfigDocument

namespace {

std::vector<std::string> split_lines(std::string_view text) {
    std::vector<std::string> lines;
    std::string cur;
    for (char c : text) {
        if (c == '\n') {
            if (!cur.empty() && cur.back() == '\r') cur.pop_back();
            lines.push_back(cur);
            cur.clear();
        } else {
            cur += c;
        }
    }
    if (!cur.empty()) lines.push_back(cur);
    return lines;
}

std::string type_name(const toml::node& n) {
    switch (n.type()) {
        case toml::node_type::table:
            return "a table";
        case toml::node_type::array:
            return "an array";
        case toml::node_type::string:
            return "a string";
        case toml::node_type::integer:
            return "an integer";
        case toml::node_type::floating_point:
            return "a number";
        case toml::node_type::boolean:
            return "a boolean";
        case toml::node_type::date:
            return "a date";
        case toml::node_type::time:
            return "a time";
        case toml::node_type::date_time:
            return "a date-time";
        default:
            return "nothing";
    }
}

std::string join_path(const std::string& path, std::string_view key) {
    return path.empty() ? std::string(key) : path + "." + std::string(key);
}

}  // namespace

ConfigDocument::ConfigDocument()
    : table_(std::make_unique<toml::table>()), resolved_(std::make_unique<toml::table>()) {}
ConfigDocument::~ConfigDocument() = default;

std::shared_ptr<ConfigDocument> ConfigDocument::parse_string(std::string_view text,
                                                             const std::string& name) {
    std::shared_ptr<ConfigDocument> doc(new ConfigDocument());
    doc->name_ = name;
    doc->lines_ = split_lines(text);
    try {
        *doc->table_ = toml::parse(text, name);
    } catch (const toml::parse_error& e) {
        const auto& b = e.source().begin;
        throw InputError({name, static_cast<int>(b.line), static_cast<int>(b.column)}, "",
                         "TOML syntax error: " + std::string(e.description()),
                         doc->source_line(static_cast<int>(b.line)));
    }
    return doc;
}

std::shared_ptr<ConfigDocument> ConfigDocument::parse_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError({path, 0, 0}, "", "cannot open the file for reading");
    std::ostringstream ss;
    ss << in.rdbuf();
    return parse_string(ss.str(), path);
}

std::shared_ptr<ConfigDocument> ConfigDocument::empty(const std::string& name) {
    std::shared_ptr<ConfigDocument> doc(new ConfigDocument());
    doc->name_ = name;
    return doc;
}

ConfigTable ConfigDocument::root() {
    return ConfigTable(shared_from_this(), table_.get(), resolved_.get(), "");
}

std::string ConfigDocument::source_line(int line) const {
    if (line <= 0 || line > static_cast<int>(lines_.size())) return {};
    return lines_[static_cast<size_t>(line - 1)];
}

std::string ConfigDocument::resolved_toml() const {
    std::ostringstream os;
    os << *resolved_ << '\n';
    return os.str();
}

void ConfigDocument::add_resolved_section(
    const std::string& name, const std::vector<std::pair<std::string, std::string>>& entries) {
    toml::table t;
    for (const auto& [k, v] : entries) t.insert_or_assign(k, v);
    resolved_->insert_or_assign(name, std::move(t));
}

// ---------------------------------------------------------------------------------------------
// ConfigTable

ConfigTable::ConfigTable(std::shared_ptr<ConfigDocument> doc, const toml::table* table,
                         toml::table* resolved, std::string path)
    : doc_(std::move(doc)), table_(table), resolved_(resolved), path_(std::move(path)) {}

std::string ConfigTable::key_path(std::string_view key) const {
    return join_path(path_, key);
}

const toml::node* ConfigTable::find(std::string_view key) const {
    return table_ ? table_->get(key) : nullptr;
}

bool ConfigTable::has(std::string_view key) const {
    return find(key) != nullptr;
}

void ConfigTable::mark(std::string_view key) const {
    doc_->used_[path_].insert(std::string(key));
    auto& asked = doc_->asked_[path_];
    if (std::find(asked.begin(), asked.end(), key) == asked.end()) asked.emplace_back(key);
}

SourceLocation ConfigTable::location(std::string_view key) const {
    if (table_) {
        for (auto&& [k, v] : *table_) {
            if (k.str() == key) {
                const auto& b = v.source().begin;
                return {doc_->name(), static_cast<int>(b.line), static_cast<int>(b.column)};
            }
        }
        const auto& b = table_->source().begin;
        return {doc_->name(), static_cast<int>(b.line), static_cast<int>(b.column)};
    }
    return {doc_->name(), 0, 0};
}

void ConfigTable::fail_at(const toml::node* n, std::string_view key,
                          const std::string& message) const {
    SourceLocation where{doc_->name(), 0, 0};
    if (n) {
        where.line = static_cast<int>(n->source().begin.line);
        where.column = static_cast<int>(n->source().begin.column);
    } else {
        where = location(key);
    }
    throw InputError(where, key_path(key), message, doc_->source_line(where.line));
}

void ConfigTable::fail(std::string_view key, const std::string& message) const {
    const toml::node* n = find(key);
    if (!n && table_) {
        // A required key is missing: if the table holds a key that is not asked for and is
        // spelled almost like it, the real error is that misspelling (say so, at its line).
        const auto u = doc_->used_.find(path_);
        std::string best;
        int best_d = 1 << 30, line = 0, column = 0;
        for (auto&& [k, v] : *table_) {
            const std::string cand(k.str());
            if (u != doc_->used_.end() && u->second.count(cand)) continue;
            const int d = edit_distance(cand, std::string(key));
            if (d < best_d) {
                best_d = d, best = cand;
                line = static_cast<int>(k.source().begin.line);
                column = static_cast<int>(k.source().begin.column);
            }
        }
        if (!best.empty() && best_d <= std::max<int>(2, static_cast<int>(key.size()) / 3))
            throw InputError({doc_->name(), line, column}, key_path(best),
                             "unknown key (did you mean '" + std::string(key) + "'?); " + message,
                             doc_->source_line(line));
    }
    fail_at(n, key, message);
}

void ConfigTable::fail_item(std::string_view key, std::size_t index,
                            const std::string& message) const {
    const toml::node* n = find(key);
    if (n && n->is_array() && index < n->as_array()->size())
        fail_at(n->as_array()->get(index), key, message);
    fail(key, message);
}

double ConfigTable::to_number(std::string_view key, const toml::node& n, Range range) const {
    double v = 0;
    if (n.is_integer())
        v = static_cast<double>(n.as_integer()->get());
    else if (n.is_floating_point())
        v = n.as_floating_point()->get();
    else
        fail_at(&n, key, "expected a number, got " + type_name(n));
    if (!std::isfinite(v)) fail_at(&n, key, "expected a finite number, got " + std::to_string(v));
    if (!range.contains(v)) {
        std::ostringstream os;
        os << "expected a number in " << range.describe() << ", got " << v;
        fail_at(&n, key, os.str());
    }
    return v;
}

double ConfigTable::number(std::string_view key, double fallback, Range range) {
    mark(key);
    const toml::node* n = find(key);
    const double v = n ? to_number(key, *n, range) : fallback;
    resolved_->insert_or_assign(key, v);
    return v;
}

double ConfigTable::number(std::string_view key, Range range) {
    mark(key);
    const toml::node* n = find(key);
    if (!n) fail(key, "required number is missing (expected a number in " + range.describe() + ")");
    const double v = to_number(key, *n, range);
    resolved_->insert_or_assign(key, v);
    return v;
}

std::optional<std::vector<std::string>> ConfigTable::optional_string_list(std::string_view key) {
    mark(key);
    if (!find(key)) return std::nullopt;
    return string_list(key);
}

std::optional<std::string> ConfigTable::optional_string(std::string_view key) {
    mark(key);
    if (!find(key)) return std::nullopt;
    return string(key);
}

std::optional<double> ConfigTable::optional_number(std::string_view key, Range range) {
    mark(key);
    const toml::node* n = find(key);
    if (!n) return std::nullopt;
    const double v = to_number(key, *n, range);
    resolved_->insert_or_assign(key, v);
    return v;
}

std::int64_t ConfigTable::integer(std::string_view key, Range range) {
    mark(key);
    const toml::node* n = find(key);
    if (!n)
        fail(key, "required integer is missing (expected an integer in " + range.describe() + ")");
    return integer(key, 0, range);
}

std::int64_t ConfigTable::integer(std::string_view key, std::int64_t fallback, Range range) {
    mark(key);
    const toml::node* n = find(key);
    std::int64_t v = fallback;
    if (n) {
        if (n->is_integer()) {
            v = n->as_integer()->get();
        } else if (n->is_floating_point()) {
            const double x = n->as_floating_point()->get();
            if (!std::isfinite(x)) fail_at(n, key, "expected a finite integer");
            if (std::floor(x) != x)
                fail_at(n, key, "expected an integer, got a number with a fractional part");
            if (!range.contains(x) || std::fabs(x) >= 9.0e18) {
                std::ostringstream os;
                os << "expected an integer in " << range.describe() << ", got " << x;
                fail_at(n, key, os.str());
            }
            v = static_cast<std::int64_t>(x);
        } else {
            fail_at(n, key, "expected an integer, got " + type_name(*n));
        }
        if (!range.contains(static_cast<double>(v)))
            fail_at(n, key,
                    "expected an integer in " + range.describe() + ", got " + std::to_string(v));
    }
    resolved_->insert_or_assign(key, v);
    return v;
}

std::optional<std::int64_t> ConfigTable::optional_integer(std::string_view key, Range range) {
    if (!has(key)) {
        mark(key);
        return std::nullopt;
    }
    return integer(key, 0, range);
}

bool ConfigTable::boolean(std::string_view key, bool fallback) {
    mark(key);
    const toml::node* n = find(key);
    bool v = fallback;
    if (n) {
        if (!n->is_boolean()) fail_at(n, key, "expected true or false, got " + type_name(*n));
        v = n->as_boolean()->get();
    }
    resolved_->insert_or_assign(key, v);
    return v;
}

std::string ConfigTable::string(std::string_view key, std::string fallback) {
    mark(key);
    const toml::node* n = find(key);
    std::string v = std::move(fallback);
    if (n) {
        if (!n->is_string()) fail_at(n, key, "expected a string, got " + type_name(*n));
        v = n->as_string()->get();
    }
    resolved_->insert_or_assign(key, v);
    return v;
}

std::string ConfigTable::string(std::string_view key) {
    mark(key);
    if (!find(key)) fail(key, "required string is missing");
    return string(key, std::string());
}

std::string ConfigTable::choice(std::string_view key, std::string fallback,
                                std::initializer_list<std::string_view> choices) {
    return choice(key, std::move(fallback),
                  std::vector<std::string>(choices.begin(), choices.end()));
}

std::string ConfigTable::choice(std::string_view key, std::string fallback,
                                const std::vector<std::string>& choices) {
    const std::string v = string(key, std::move(fallback));
    for (const auto& c : choices)
        if (c == v) return v;
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "" : ", ") + std::string("\"") + c + "\"";
    std::string msg = "expected one of " + list + ", got \"" + v + "\"";
    const std::string best = nearest_name(v, choices, 2);
    if (!best.empty()) msg += " (did you mean \"" + best + "\"?)";
    fail(key, msg);
}

std::vector<std::string> ConfigTable::string_list(std::string_view key) {
    mark(key);
    const toml::node* n = find(key);
    if (!n) fail(key, "required list of strings is missing");
    if (!n->is_array()) fail_at(n, key, "expected an array of strings, got " + type_name(*n));
    std::vector<std::string> out;
    toml::array resolved;
    for (const toml::node& item : *n->as_array()) {
        if (!item.is_string())
            fail_at(&item, key, "expected an array of strings, found " + type_name(item));
        out.push_back(item.as_string()->get());
        resolved.push_back(out.back());
    }
    resolved_->insert_or_assign(key, std::move(resolved));
    return out;
}

std::optional<std::vector<double>> ConfigTable::optional_number_list(std::string_view key,
                                                                     Range range) {
    mark(key);
    const toml::node* n = find(key);
    if (!n) return std::nullopt;
    if (!n->is_array()) fail_at(n, key, "expected an array of numbers, got " + type_name(*n));
    std::vector<double> out;
    toml::array resolved;
    for (const toml::node& item : *n->as_array()) {
        out.push_back(to_number(key, item, range));
        resolved.push_back(out.back());
    }
    resolved_->insert_or_assign(key, std::move(resolved));
    return out;
}

std::optional<std::array<double, 3>> ConfigTable::optional_rgb(std::string_view key, Range range) {
    mark(key);
    const toml::node* n = find(key);
    if (!n) return std::nullopt;
    std::array<double, 3> v{};
    if (n->is_array()) {
        const toml::array& a = *n->as_array();
        if (a.size() != 3)
            fail_at(n, key,
                    "expected 3 numbers [R, G, B], got an array of " + std::to_string(a.size()));
        for (size_t i = 0; i < 3; ++i) v[i] = to_number(key, *a.get(i), range);
    } else if (n->is_number()) {
        const double x = to_number(key, *n, range);
        v = {x, x, x};
    } else {
        fail_at(n, key, "expected 3 numbers [R, G, B] or one number, got " + type_name(*n));
    }
    toml::array out;
    for (double x : v) out.push_back(x);
    resolved_->insert_or_assign(key, std::move(out));
    return v;
}

std::array<double, 3> ConfigTable::rgb(std::string_view key, Range range) {
    auto v = optional_rgb(key, range);
    if (!v)
        fail(key, "required value is missing (expected 3 numbers [R, G, B] in " + range.describe() +
                      ")");
    return *v;
}

std::optional<Vec3> ConfigTable::optional_vec3(std::string_view key, Range range) {
    mark(key);
    const toml::node* n = find(key);
    if (!n) return std::nullopt;
    if (!n->is_array() || n->as_array()->size() != 3)
        fail_at(n, key,
                "expected 3 numbers [x, y, z], got " +
                    (n->is_array() ? "an array of " + std::to_string(n->as_array()->size())
                                   : type_name(*n)));
    const toml::array& a = *n->as_array();
    const Vec3 v{to_number(key, *a.get(0), range), to_number(key, *a.get(1), range),
                 to_number(key, *a.get(2), range)};
    toml::array out;
    for (double x : {v.x, v.y, v.z}) out.push_back(x);
    resolved_->insert_or_assign(key, std::move(out));
    return v;
}

Vec3 ConfigTable::vec3(std::string_view key, Range range) {
    auto v = optional_vec3(key, range);
    if (!v) fail(key, "required value is missing (expected 3 numbers [x, y, z])");
    return *v;
}

std::optional<ConfigTable> ConfigTable::table(std::string_view key) {
    mark(key);
    const toml::node* n = find(key);
    if (!n) return std::nullopt;
    if (!n->is_table()) fail_at(n, key, "expected a table, got " + type_name(*n));
    auto [it, inserted] = resolved_->insert_or_assign(key, toml::table{});
    (void)inserted;
    return ConfigTable(doc_, n->as_table(), it->second.as_table(), key_path(key));
}

ConfigTable ConfigTable::require_table(std::string_view key) {
    auto t = table(key);
    if (!t) fail(key, "required table [" + key_path(key) + "] is missing");
    return *t;
}

ConfigTable ConfigTable::table_or_empty(std::string_view key) {
    if (auto t = table(key)) return *t;
    auto [it, inserted] = resolved_->insert_or_assign(key, toml::table{});
    (void)inserted;
    return ConfigTable(doc_, nullptr, it->second.as_table(), key_path(key));
}

std::vector<ConfigTable> ConfigTable::table_array(std::string_view key) {
    mark(key);
    std::vector<ConfigTable> out;
    const toml::node* n = find(key);
    if (!n) return out;
    if (!n->is_array_of_tables())
        fail_at(n, key,
                "expected an array of tables ([[" + key_path(key) + "]]), got " + type_name(*n));
    toml::array resolved_array;
    const toml::array& a = *n->as_array();
    for (size_t i = 0; i < a.size(); ++i) resolved_array.push_back(toml::table{});
    auto [it, inserted] = resolved_->insert_or_assign(key, std::move(resolved_array));
    (void)inserted;
    toml::array& ra = *it->second.as_array();
    for (size_t i = 0; i < a.size(); ++i) {
        const toml::table* src = a.get_as<toml::table>(i);
        toml::table* dst = ra.get_as<toml::table>(i);
        if (!src || !dst) fail_at(n, key, "expected an array of tables");
        out.push_back(ConfigTable(doc_, src, dst, key_path(key) + "[" + std::to_string(i) + "]"));
    }
    return out;
}

void ConfigTable::record(std::string_view key, double value) {
    resolved_->insert_or_assign(key, value);
}
void ConfigTable::record(std::string_view key, std::int64_t value) {
    resolved_->insert_or_assign(key, value);
}
void ConfigTable::record(std::string_view key, const std::string& value) {
    resolved_->insert_or_assign(key, value);
}
void ConfigTable::record(std::string_view key, const std::vector<double>& values) {
    toml::array arr;
    for (double v : values) arr.push_back(v);
    resolved_->insert_or_assign(key, std::move(arr));
}
void ConfigTable::record(std::string_view key, const std::vector<std::vector<double>>& rows) {
    toml::array arr;
    for (const auto& row : rows) {
        toml::array r;
        for (double v : row) r.push_back(v);
        arr.push_back(std::move(r));
    }
    resolved_->insert_or_assign(key, std::move(arr));
}

namespace {

// Walks the parsed tree and reports the first key that no getter marked as used.
void check_unused(const ConfigDocument& doc, const toml::table& t, const std::string& path,
                  const std::map<std::string, std::set<std::string>>& used,
                  const std::map<std::string, std::vector<std::string>>& asked,
                  const std::string& file) {
    const auto u = used.find(path);
    for (auto&& [k, v] : t) {
        const std::string key(k.str());
        const bool is_used = u != used.end() && u->second.count(key) > 0;
        if (!is_used) {
            std::string msg = "unknown key";
            const auto a = asked.find(path);
            if (a != asked.end()) {
                const std::string best = nearest_name(key, a->second, suggestion_distance(key));
                if (!best.empty()) msg += " (did you mean '" + best + "'?)";
                std::string list;
                for (const auto& cand : a->second) list += (list.empty() ? "" : ", ") + cand;
                msg += "; valid keys here: " + list;
            } else {
                msg += "; this table takes no keys here";
            }
            const auto& b = k.source().begin;
            const int line = static_cast<int>(b.line);
            throw InputError({file, line, static_cast<int>(b.column)}, join_path(path, key), msg,
                             doc.source_line(line));
        }
        if (v.is_table()) {
            check_unused(doc, *v.as_table(), join_path(path, key), used, asked, file);
        } else if (v.is_array_of_tables()) {
            const toml::array& a = *v.as_array();
            for (size_t i = 0; i < a.size(); ++i)
                check_unused(doc, *a.get(i)->as_table(),
                             join_path(path, key) + "[" + std::to_string(i) + "]", used, asked,
                             file);
        }
    }
}

}  // namespace

void ConfigTable::finish() const {
    if (table_) check_unused(*doc_, *table_, path_, doc_->used_, doc_->asked_, doc_->name());
}

}  // namespace ssslab
