#pragma once
// Numbers as text, written once: the tables, CSVs, keys, reports and messages of ssslab format
// their numbers through these (printf's conversions, so the text is the same wherever the C
// library conforms).

#include <cstddef>
#include <cstdio>
#include <string>

namespace ssslab {

namespace detail {
// The conversion's text at its full length (literal formats: -Wformat-nonliteral stays quiet).
inline std::string printf_number(bool fixed, int precision, double v) {
    auto write = [&](char* out, std::size_t size) {
        return fixed ? std::snprintf(out, size, "%.*f", precision, v)
                     : std::snprintf(out, size, "%.*g", precision, v);
    };
    const int n = write(nullptr, 0);
    std::string s(static_cast<std::size_t>(n > 0 ? n : 0), '\0');
    write(s.data(), s.size() + 1);
    return s;
}
}  // namespace detail

/// `v` with `digits` significant digits, as printf's "%.*g" writes it; with 17 (the default) the
/// text reads back as the same double.
inline std::string format_g(double v, int digits = 17) {
    return detail::printf_number(false, digits, v);
}

/// `v` with `decimals` digits after the point, as printf's "%.*f" writes it.
inline std::string format_f(double v, int decimals) {
    return detail::printf_number(true, decimals, v);
}

}  // namespace ssslab
