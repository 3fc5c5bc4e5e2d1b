#include "mcml/mco.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace ssslab::mcml {

namespace {

// printf into a std::string (the original's fprintf formats, verbatim).
[[gnu::format(printf, 2, 3)]] void out(std::string& s, const char* fmt, ...) {
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    const int n = std::vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    if (n >= static_cast<int>(sizeof buf)) {
        std::string big(static_cast<size_t>(n) + 1, '\0');
        va_start(ap, fmt);
        std::vsnprintf(big.data(), big.size(), fmt, ap);
        va_end(ap);
        big.pop_back();
        s += big;
    } else {
        s.append(buf, static_cast<size_t>(n));
    }
}

void write_1d(std::string& s, const char* header, const std::vector<double>& v) {
    s += header;
    for (double x : v) out(s, "%12.4E\n", x);
    s += "\n";
}

void write_2d(std::string& s, const char* const lines[6], const std::vector<double>& v, int n1,
              int n2) {
    out(s, "%s\n%s\n%s\n%s\n%s\n%s\n", lines[0], lines[1], lines[2], lines[3], lines[4], lines[5]);
    for (int i = 0; i < n1; i++)
        for (int j = 0; j < n2; j++) {
            out(s, "%12.4E ",
                v[static_cast<size_t>(i) * static_cast<size_t>(n2) + static_cast<size_t>(j)]);
            if ((i * n2 + j + 1) % 5 == 0) s += "\n";
        }
    s += "\n";
}

}  // namespace

std::string format_mco(const RunSpec& run, const McoResult& r, std::int64_t photons,
                       double user_seconds) {
    std::string s;
    s.reserve(1 << 16);
    // WriteVersion()
    out(s, "%s \t# Version number of the file format.\n\n", run.out_format == 'B' ? "B1" : "A1");
    s += "####\n# Data categories include: \n";
    s += "# InParm, RAT, \n";
    s += "# A_l, A_z, Rd_r, Rd_a, Tt_r, Tt_a, \n";
    s += "# A_rz, Rd_ra, Tt_ra \n####\n\n";
    // PunchTime()'s report
    out(s, "# User time: %8.0f sec = %8.2f hr.  %s\n", user_seconds, user_seconds / 3600.0,
        " Simulation time of this run.");
    s += "\n";
    // WriteInParm()
    s += "InParm \t\t\t# Input parameters. cm is used.\n";
    out(s, "%s \tA\t\t# output file name, ASCII.\n", run.out_name.c_str());
    out(s, "%lld \t\t\t# No. of photons\n", static_cast<long long>(photons));
    out(s, "%G\t%G\t\t# dz, dr [cm]\n", run.grid.dz, run.grid.dr);
    out(s, "%d\t%d\t%d\t# No. of dz, dr, da.\n\n", run.grid.nz, run.grid.nr, run.grid.na);
    out(s, "%d\t\t\t\t\t# Number of layers\n", run.num_layers());
    s += "#n\tmua\tmus\tg\td\t# One line for each layer\n";
    out(s, "%G\t\t\t\t\t# n for medium above\n", run.layers[0].n);
    int i;
    for (i = 1; i <= run.num_layers(); i++) {
        const Layer& l = run.layers[static_cast<size_t>(i)];
        out(s, "%G\t%G\t%G\t%G\t%G\t# layer %d\n", l.n, l.mua, l.mus, l.g, l.z1 - l.z0, i);
    }
    out(s, "%G\t\t\t\t\t# n for medium below\n\n", run.layers[static_cast<size_t>(i)].n);
    // WriteRAT()
    s += "RAT #Reflectance, absorption, transmission. \n";
    out(s, "%-14.6G \t#Specular reflectance [-]\n", r.rsp);
    out(s, "%-14.6G \t#Diffuse reflectance [-]\n", r.rd);
    out(s, "%-14.6G \t#Absorbed fraction [-]\n", r.a);
    out(s, "%-14.6G \t#Transmittance [-]\n", r.tt);
    s += "\n";
    // WriteA_layer()
    s += "A_l #Absorption as a function of layer. [-]\n";
    for (i = 1; i <= run.num_layers(); i++) out(s, "%12.4G\n", r.a_l[static_cast<size_t>(i)]);
    s += "\n";
    write_1d(s, "A_z #A[0], [1],..A[nz-1]. [1/cm]\n", r.a_z);
    write_1d(s, "Rd_r #Rd[0], [1],..Rd[nr-1]. [1/cm2]\n", r.rd_r);
    write_1d(s, "Rd_a #Rd[0], [1],..Rd[na-1]. [sr-1]\n", r.rd_a);
    write_1d(s, "Tt_r #Tt[0], [1],..Tt[nr-1]. [1/cm2]\n", r.tt_r);
    write_1d(s, "Tt_a #Tt[0], [1],..Tt[na-1]. [sr-1]\n", r.tt_a);
    static const char* const kArz[6] = {"# A[r][z]. [1/cm3]",
                                        "# A[0][0], [0][1],..[0][nz-1]",
                                        "# A[1][0], [1][1],..[1][nz-1]",
                                        "# ...",
                                        "# A[nr-1][0], [nr-1][1],..[nr-1][nz-1]",
                                        "A_rz"};
    static const char* const kRdra[6] = {"# Rd[r][angle]. [1/(cm2sr)].",
                                         "# Rd[0][0], [0][1],..[0][na-1]",
                                         "# Rd[1][0], [1][1],..[1][na-1]",
                                         "# ...",
                                         "# Rd[nr-1][0], [nr-1][1],..[nr-1][na-1]",
                                         "Rd_ra"};
    static const char* const kTtra[6] = {"# Tt[r][angle]. [1/(cm2sr)].",
                                         "# Tt[0][0], [0][1],..[0][na-1]",
                                         "# Tt[1][0], [1][1],..[1][na-1]",
                                         "# ...",
                                         "# Tt[nr-1][0], [nr-1][1],..[nr-1][na-1]",
                                         "Tt_ra"};
    write_2d(s, kArz, r.a_rz, run.grid.nr, run.grid.nz);
    write_2d(s, kRdra, r.rd_ra, run.grid.nr, run.grid.na);
    write_2d(s, kTtra, r.tt_ra, run.grid.nr, run.grid.na);
    return s;
}

McoFile parse_mco(const std::string& text, const std::string& name) {
    std::istringstream in(text);
    std::string line;
    int lineno = 0;
    McoFile f;
    auto fail = [&](const std::string& msg) -> void {
        throw InputError({name, lineno, 0}, "", msg, line);
    };
    // A count in the file: a whole number in [lo, hi], refused otherwise (a cast of an
    // out-of-range double to an integer is undefined; found by fuzz/fuzz_mco.cpp).
    auto count = [&](double v, double lo, double hi, const std::string& what) {
        if (!(v >= lo && v <= hi) || v != std::floor(v))
            fail(what + " must be a whole number in [" +
                 std::to_string(static_cast<long long>(lo)) + ", " +
                 std::to_string(static_cast<long long>(hi)) + "]");
        return static_cast<std::int64_t>(v);
    };
    auto next_line = [&]() -> bool {
        if (!std::getline(in, line)) return false;
        ++lineno;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return true;
    };
    auto numbers = [&](const std::string& l) {
        std::vector<double> v;
        std::istringstream ls(l.substr(0, l.find('#')));
        std::string tok;
        while (ls >> tok) {
            char* end = nullptr;
            const double x = std::strtod(tok.c_str(), &end);
            if (*end != '\0') fail("expected a number, found \"" + tok + "\"");
            v.push_back(x);
        }
        return v;
    };
    // Read numbers until a blank line.
    auto block = [&]() {
        std::vector<double> v;
        while (next_line() && !line.empty()) {
            auto x = numbers(line);
            v.insert(v.end(), x.begin(), x.end());
        }
        return v;
    };
    bool version_ok = false;
    while (next_line()) {
        const std::string key = line.substr(0, line.find_first_of(" \t"));
        if (key == "A1" || key == "B1") {
            version_ok = true;
        } else if (key == "InParm") {
            next_line();  // file name
            next_line();
            auto p = numbers(line);
            if (p.size() != 1) fail("expected the number of photons");
            f.photons = count(p[0], 0, 9e15, "the number of photons");
            next_line();
            p = numbers(line);
            if (p.size() != 2) fail("expected dz dr");
            f.grid.dz = p[0], f.grid.dr = p[1];
            next_line();
            p = numbers(line);
            if (p.size() != 3) fail("expected nz nr na");
            f.grid.nz = static_cast<int>(count(p[0], 1, 1e8, "nz"));
            f.grid.nr = static_cast<int>(count(p[1], 1, 1e8, "nr"));
            f.grid.na = static_cast<int>(count(p[2], 1, 1e8, "na"));
            while (next_line() && numbers(line).empty()) {
            }
            p = numbers(line);
            if (p.size() != 1) fail("expected the number of layers");
            f.num_layers = static_cast<int>(count(p[0], 1, 1e6, "the number of layers"));
        } else if (key == "RAT") {
            double* dst[4] = {&f.result.rsp, &f.result.rd, &f.result.a, &f.result.tt};
            for (double* d : dst) {
                next_line();
                auto p = numbers(line);
                if (p.size() != 1) fail("expected one number in RAT");
                *d = p[0];
            }
        } else if (key == "A_l") {
            auto v = block();
            f.result.a_l.assign(1, 0.0);
            f.result.a_l.insert(f.result.a_l.end(), v.begin(), v.end());
            f.result.a_l.push_back(0.0);
        } else if (key == "A_z") {
            f.result.a_z = block();
        } else if (key == "Rd_r") {
            f.result.rd_r = block();
        } else if (key == "Rd_a") {
            f.result.rd_a = block();
        } else if (key == "Tt_r") {
            f.result.tt_r = block();
        } else if (key == "Tt_a") {
            f.result.tt_a = block();
        } else if (key == "A_rz") {
            f.result.a_rz = block();
        } else if (key == "Rd_ra") {
            f.result.rd_ra = block();
        } else if (key == "Tt_ra") {
            f.result.tt_ra = block();
        }
    }
    if (!version_ok) throw InputError({name, 1, 0}, "", "not an MCML .mco file (no A1 header)");
    const size_t nr = static_cast<size_t>(f.grid.nr), nz = static_cast<size_t>(f.grid.nz),
                 na = static_cast<size_t>(f.grid.na);
    if (f.result.rd_r.size() != nr || f.result.a_z.size() != nz || f.result.rd_a.size() != na ||
        f.result.a_rz.size() != nr * nz || f.result.rd_ra.size() != nr * na ||
        f.result.tt_ra.size() != nr * na)
        throw InputError({name, 0, 0}, "", "array sizes do not match the grid in InParm");
    return f;
}

McoFile read_mco(const std::string& path) {
    std::string text;
    try {
        text = read_file(path);
    } catch (const IoError&) {
        throw InputError({path, 0, 0}, "", "cannot open the .mco file for reading");
    }
    return parse_mco(text, path);
}

}  // namespace ssslab::mcml
