// The spellings of the enums a user writes (command-line values, TOML keys, provenance): one
// table per enum, beside its declaration, from which its one parser and one printer come, so
// that a value is validated in one place and printed as it is read back.
//
//   template <>
//   struct EnumNames<SssMethod> {
//       static constexpr std::array<std::pair<SssMethod, std::string_view>, 3> table = {{
//           {SssMethod::kSeparable, "separable"}, ...}};
//   };
//
// name_of(e) prints, parse_name<E>(s) parses (nullopt for an unknown spelling), names_of<E>()
// lists the spellings in table order; ConfigTable::enumerated (core/config.h) and the command
// line's one_of_enum (experiments/cli/common.h) validate with them and say what was expected.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ssslab {

template <class E>
struct EnumNames;  // specialised beside each enum a user spells

template <class E>
constexpr std::string_view name_of(E e) {
    for (const auto& [v, n] : EnumNames<E>::table)
        if (v == e) return n;
    return "?";
}

template <class E>
constexpr std::optional<E> parse_name(std::string_view s) {
    for (const auto& [v, n] : EnumNames<E>::table)
        if (n == s) return v;
    return std::nullopt;
}

template <class E>
std::vector<std::string> names_of() {
    std::vector<std::string> out;
    for (const auto& [v, n] : EnumNames<E>::table) out.emplace_back(n);
    return out;
}

/// "a, b, c": the spellings joined, for messages.
template <class E>
std::string names_joined(std::string_view separator = ", ") {
    std::string out;
    for (const auto& [v, n] : EnumNames<E>::table) {
        if (!out.empty()) out += separator;
        out += n;
    }
    return out;
}

}  // namespace ssslab
