#include "core/error.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string_view>
#include <vector>

namespace ssslab {

namespace {

// Length of the valid UTF-8 sequence at s[i] (1 for ASCII), or 0 if the bytes there are not one.
size_t utf8_length(std::string_view s, size_t i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) return 1;
    size_t n = 0;
    unsigned min = 0;
    if ((c & 0xE0) == 0xC0)
        n = 2, min = 0x80;
    else if ((c & 0xF0) == 0xE0)
        n = 3, min = 0x800;
    else if ((c & 0xF8) == 0xF0)
        n = 4, min = 0x10000;
    else
        return 0;
    if (i + n > s.size()) return 0;
    unsigned cp = c & (0xFF >> (n + 1));
    for (size_t k = 1; k < n; ++k) {
        const auto b = static_cast<unsigned char>(s[i + k]);
        if ((b & 0xC0) != 0x80) return 0;
        cp = (cp << 6) | (b & 0x3F);
    }
    if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
    return n;
}

// Whether a byte is one a terminal shows as itself: not a control character (tab excepted).
bool control(unsigned char c) {
    return (c < 0x20 && c != '\t') || c == 0x7F;
}

// Whether a source line can be shown as it is: UTF-8 text without control characters.
bool printable_line(std::string_view s) {
    for (size_t i = 0; i < s.size();) {
        const size_t n = utf8_length(s, i);
        if (n == 0 || (n == 1 && control(static_cast<unsigned char>(s[i])))) return false;
        i += n;
    }
    return true;
}

// `s` with every byte that is not text (control characters other than tab and newline, invalid
// UTF-8) written as \xNN, so that a message quoting the input never echoes raw bytes.
std::string printable(std::string_view s) {
    std::string out;
    out.reserve(s.size());
    for (size_t i = 0; i < s.size();) {
        const size_t n = utf8_length(s, i);
        if (n == 0 || (n == 1 && control(static_cast<unsigned char>(s[i])) && s[i] != '\n')) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", static_cast<unsigned char>(s[i]));
            out += buf;
            ++i;
        } else {
            out.append(s.substr(i, n));
            i += n;
        }
    }
    return out;
}

std::string format_input_error(const SourceLocation& where, const std::string& key,
                               const std::string& message, const std::string& line_text) {
    std::ostringstream os;
    os << (where.file.empty() ? std::string("<input>") : where.file);
    if (where.line > 0) {
        os << ':' << where.line;
        if (where.column > 0) os << ':' << where.column;
    }
    os << ": error: ";
    if (!key.empty()) os << "key '" << printable(key) << "': ";
    os << printable(message);
    if (!line_text.empty() && !printable_line(line_text)) {
        // The bytes of a binary file (or stray control characters) would garble the terminal.
        os << "\n    (the line is not shown: it holds bytes that are not text (NUL, control "
              "characters or invalid UTF-8); is this a binary file?)";
    } else if (!line_text.empty()) {
        os << "\n    " << line_text;
        if (where.column > 0) {
            os << "\n    ";
            // Keep tabs so that the caret lines up under the offending column.
            for (int i = 0; i + 1 < where.column && i < static_cast<int>(line_text.size()); ++i)
                os << (line_text[static_cast<size_t>(i)] == '\t' ? '\t' : ' ');
            os << '^';
        }
    }
    return os.str();
}

}  // namespace

InputError::InputError(SourceLocation where, std::string key, std::string message,
                       std::string line_text)
    : std::runtime_error(format_input_error(where, key, message, line_text)),
      where_(std::move(where)),
      key_(std::move(key)),
      message_(std::move(message)) {}

std::string read_source_line(const std::string& file, int line) {
    if (line <= 0) return {};
    std::ifstream in(file, std::ios::binary);
    std::string s;
    for (int i = 1; std::getline(in, s); ++i) {
        if (i == line) {
            if (!s.empty() && s.back() == '\r') s.pop_back();
            return s;
        }
    }
    return {};
}

int edit_distance(const std::string& a, const std::string& b) {
    std::vector<int> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = static_cast<int>(j);
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = static_cast<int>(i);
        for (size_t j = 1; j <= b.size(); ++j) {
            const int sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
        }
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

std::string nearest_name(const std::string& name, const std::vector<std::string>& candidates,
                         int max_distance) {
    std::string best;
    int best_d = max_distance + 1;
    for (const std::string& c : candidates) {
        const int d = edit_distance(name, c);
        if (d < best_d) best_d = d, best = c;
    }
    return best;
}

int suggestion_distance(const std::string& name) {
    return std::max<int>(2, static_cast<int>(name.size()) / 3);
}

}  // namespace ssslab
