#include "core/error.h"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <vector>

namespace ssslab {

namespace {

std::string format_input_error(const SourceLocation& where, const std::string& key,
                               const std::string& message, const std::string& line_text) {
    std::ostringstream os;
    os << (where.file.empty() ? std::string("<input>") : where.file);
    if (where.line > 0) {
        os << ':' << where.line;
        if (where.column > 0) os << ':' << where.column;
    }
    os << ": error: ";
    if (!key.empty()) os << "key '" << key << "': ";
    os << message;
    if (!line_text.empty()) {
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

}  // namespace ssslab
