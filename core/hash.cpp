#include "core/hash.h"

#include <xxhash.h>

#include <cstdio>

namespace ssslab {

namespace {
std::string number(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v == 0.0 ? 0.0 : v);  // -0 and 0 alike
    return buf;
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

std::string ContentKey::hex() const {
    return hash_hex(text_);
}

}  // namespace ssslab
