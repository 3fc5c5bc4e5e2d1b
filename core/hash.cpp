#include "core/hash.h"

#include "core/atomic_file.h"
#include "core/format.h"

#include <xxhash.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <vector>

namespace ssslab {

namespace {
std::string number(double v) {
    return format_g(v == 0.0 ? 0.0 : v, 17);  // -0 and 0 alike
}
}  // namespace

ContentKey& ContentKey::add(std::string_view name, std::string_view value) {
    text_ += name;
    text_ += '=';
    // Values may hold any text (a description); escape the separators.
    for (char c : value) {
        if (c == '\n')
            text_ += "\\n";
        else if (c == '\\')
            text_ += "\\\\";
        else
            text_ += c;
    }
    text_ += '\n';
    return *this;
}

ContentKey& ContentKey::add(std::string_view name, double value) {
    return add(name, number(value));
}
ContentKey& ContentKey::add(std::string_view name, std::int64_t value) {
    return add(name, std::to_string(value));
}
ContentKey& ContentKey::add(std::string_view name, std::uint64_t value) {
    return add(name, std::to_string(value));
}

ContentKey& ContentKey::add(std::string_view name, const std::array<double, 3>& value) {
    return add(name, number(value[0]) + "," + number(value[1]) + "," + number(value[2]));
}

ContentKey& ContentKey::add(std::string_view name, const std::vector<double>& value) {
    std::string s;
    for (double v : value) s += (s.empty() ? "" : ",") + number(v);
    return add(name, s);
}

std::string hash_hex(std::string_view bytes) {
    const XXH128_hash_t h = XXH3_128bits(bytes.data(), bytes.size());
    char buf[33];
    std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(h.high64),
                  static_cast<unsigned long long>(h.low64));
    return buf;
}

std::string file_hash_hex(const std::string& path) {
    return hash_hex(read_file(path));
}

namespace {

// The lines of a key text as (name, value) in order; a line without '=' is its own name with an
// empty value. Repeated names get "#2", "#3", ... so that each item is compared with its twin.
std::vector<std::pair<std::string, std::string>> key_items(std::string_view text) {
    std::vector<std::pair<std::string, std::string>> items;
    std::map<std::string, int> seen;
    std::size_t pos = 0;
    while (pos < text.size()) {
        std::size_t end = text.find('\n', pos);
        if (end == std::string_view::npos) end = text.size();
        const std::string_view line = text.substr(pos, end - pos);
        pos = end + 1;
        if (line.empty()) continue;
        const std::size_t eq = line.find('=');
        std::string name(eq == std::string_view::npos ? line : line.substr(0, eq));
        std::string value(eq == std::string_view::npos ? std::string_view{} : line.substr(eq + 1));
        const int n = ++seen[name];
        if (n > 1) name += "#" + std::to_string(n);
        items.emplace_back(std::move(name), std::move(value));
    }
    return items;
}

// A value as shown in a message: numbers (and lists of them) with 8 significant digits instead
// of the key's 17, long values cut.
std::string shown(const std::string& v) {
    std::string out;
    std::size_t pos = 0;
    while (pos <= v.size()) {
        std::size_t end = v.find(',', pos);
        if (end == std::string::npos) end = v.size();
        const std::string item = v.substr(pos, end - pos);
        char* stop = nullptr;
        const double d = std::strtod(item.c_str(), &stop);
        if (!item.empty() && stop && *stop == '\0') {
            out += format_g(d, 8);
        } else {
            out += item;
        }
        if (end == v.size()) break;
        out += ", ";
        pos = end + 1;
    }
    if (out.size() <= 64) return out;
    return out.substr(0, 56) + "...";
}

}  // namespace

std::string key_difference(std::string_view before, std::string_view now, int max_items) {
    const auto a = key_items(before), b = key_items(now);
    std::map<std::string, std::string> in_b(b.begin(), b.end());
    std::map<std::string, std::string> in_a(a.begin(), a.end());
    std::vector<std::string> diffs;
    for (const auto& [name, value] : a) {
        const auto it = in_b.find(name);
        if (it == in_b.end()) {
            diffs.push_back(name + (value.empty() ? "" : " = " + shown(value)) +
                            ": only in the earlier input");
        } else if (it->second != value) {
            const bool opaque = value.size() == 32 && it->second.size() == 32 &&
                                value.find_first_not_of("0123456789abcdef") == std::string::npos;
            diffs.push_back(name + (opaque
                                        ? ": content changed"
                                        : ": was " + shown(value) + ", now " + shown(it->second)));
        }
    }
    for (const auto& [name, value] : b)
        if (!in_a.count(name))
            diffs.push_back(name + (value.empty() ? "" : " = " + shown(value)) + ": new");
    std::string out;
    const int n = static_cast<int>(diffs.size());
    for (int i = 0; i < n && i < max_items; ++i)
        out += (i ? "; " : "") + diffs[static_cast<size_t>(i)];
    if (n > max_items) out += "; and " + std::to_string(n - max_items) + " more";
    return out;
}

std::string ContentKey::hex() const {
    return hash_hex(text_);
}

}  // namespace ssslab
