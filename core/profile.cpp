#include "core/profile.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace ssslab {

const char* unit_name(LengthUnit u) {
    return name_of(u).data();
}

std::string RadialProfile::to_csv(LengthUnit unit) const {
    const char* u = unit_name(unit);
    const double len = unit == LengthUnit::kMm ? 10.0 : 1.0;  // cm -> unit
    const double area = 1.0 / (len * len);                    // 1/cm^2 -> 1/unit^2
    std::string s;
    char buf[128];
    std::snprintf(buf, sizeof buf, "r_mid_%s,r_lo_%s,r_hi_%s", u, u, u);
    s += buf;
    for (const char* c : {"R", "G", "B"}) {
        std::snprintf(buf, sizeof buf, ",Rd_%s_per_%s2,Rd_%s_se_per_%s2", c, u, c, u);
        s += buf;
    }
    s += "\n";
    for (int i = 0; i < nr; ++i) {
        const double dr = dr_cm * len;
        std::snprintf(buf, sizeof buf, "%.9g,%.9g,%.9g", (i + 0.5) * dr, i * dr, (i + 1) * dr);
        s += buf;
        for (int c = 0; c < 3; ++c) {
            std::snprintf(buf, sizeof buf, ",%.9g,%.9g",
                          rd_per_cm2[c][static_cast<size_t>(i)] * area,
                          se_per_cm2[c][static_cast<size_t>(i)] * area);
            s += buf;
        }
        s += "\n";
    }
    return s;
}

RadialProfile read_profile_csv(const std::string& path) {
    const std::string text = read_file(path);
    std::istringstream in(text);
    std::string line;
    RadialProfile p;
    p.name = path;
    int lineno = 0;
    if (!std::getline(in, line)) throw InputError({path, 1, 0}, "", "empty profile file");
    ++lineno;
    LengthUnit unit;
    if (line.rfind("r_mid_mm,", 0) == 0)
        unit = LengthUnit::kMm;
    else if (line.rfind("r_mid_cm,", 0) == 0)
        unit = LengthUnit::kCm;
    else
        throw InputError({path, 1, 1}, "", "expected a header starting with r_mid_mm or r_mid_cm",
                         line);
    const double len = unit == LengthUnit::kMm ? 10.0 : 1.0;
    std::vector<std::vector<double>> rows;
    while (std::getline(in, line)) {
        ++lineno;
        if (line.empty()) continue;
        std::vector<double> row;
        std::istringstream ls(line);
        std::string tok;
        while (std::getline(ls, tok, ',')) {
            char* end = nullptr;
            row.push_back(std::strtod(tok.c_str(), &end));
            if (end == tok.c_str() || *end != '\0')
                throw InputError({path, lineno, 0}, "", "expected a number, found \"" + tok + "\"",
                                 line);
        }
        if (row.size() != 9) throw InputError({path, lineno, 0}, "", "expected 9 columns", line);
        rows.push_back(row);
    }
    if (rows.empty()) throw InputError({path, lineno, 0}, "", "profile has no bins");
    p.nr = static_cast<int>(rows.size());
    p.dr_cm = (rows[0][2] - rows[0][1]) / len;
    for (int c = 0; c < 3; ++c) {
        p.rd_per_cm2[c].resize(rows.size());
        p.se_per_cm2[c].resize(rows.size());
        for (size_t i = 0; i < rows.size(); ++i) {
            p.rd_per_cm2[c][i] = rows[i][3 + 2 * c] * len * len;
            p.se_per_cm2[c][i] = rows[i][4 + 2 * c] * len * len;
        }
    }
    return p;
}

}  // namespace ssslab
