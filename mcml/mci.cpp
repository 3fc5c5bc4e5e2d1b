#include "mcml/mci.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <sstream>

namespace ssslab::mcml {

namespace {

struct Token {
    std::string text;
    int column;  // from 1
};

struct DataLine {
    int line = 0;  // from 1; 0 at end of file
    std::string text;
    std::vector<Token> tokens;
};

class Reader {
  public:
    Reader(std::string_view text, std::string name) : name_(std::move(name)) {
        std::string cur;
        auto flush = [&](bool last) {
            if (last && cur.empty()) return;
            if (!cur.empty() && cur.back() == '\r') cur.pop_back();
            lines_.push_back(cur);
            cur.clear();
        };
        for (char c : text) {
            if (c == '\n')
                flush(false);
            else
                cur += c;
        }
        flush(true);
    }

    const std::string& name() const { return name_; }

    [[noreturn]] void fail(int line, int column, const std::string& entry,
                           const std::string& msg) const {
        const std::string text =
            line > 0 && line <= static_cast<int>(lines_.size()) ? lines_[line - 1] : "";
        throw InputError({name_, line, column}, entry, msg, text);
    }

    // Next line with data, skipping blank and comment lines (MCML's FindDataLine()).
    DataLine next(const std::string& entry) {
        while (pos_ < lines_.size()) {
            const int lineno = static_cast<int>(pos_) + 1;
            const std::string& raw = lines_[pos_++];
            for (size_t i = 0; i < raw.size(); ++i) {
                const unsigned char c = static_cast<unsigned char>(raw[i]);
                if (c >= 0x80 || c == 0 || (c < 0x20 && c != '\t' && c != '\v' && c != '\f'))
                    fail(lineno, static_cast<int>(i) + 1, "",
                         c >= 0x80 ? "non-ASCII byte in an .mci file"
                                   : "control character in an .mci file");
            }
            const std::string data = raw.substr(0, raw.find('#'));
            DataLine dl;
            dl.line = lineno;
            dl.text = raw;
            size_t i = 0;
            while (i < data.size()) {
                while (i < data.size() && std::isspace(static_cast<unsigned char>(data[i]))) ++i;
                if (i >= data.size()) break;
                const size_t b = i;
                while (i < data.size() && !std::isspace(static_cast<unsigned char>(data[i]))) ++i;
                dl.tokens.push_back({data.substr(b, i - b), static_cast<int>(b) + 1});
            }
            if (!dl.tokens.empty()) return dl;
        }
        fail(std::max(1, static_cast<int>(lines_.size())), 0, "",
             "unexpected end of file: expected " + entry);
    }

    bool has_more_data() {
        while (pos_ < lines_.size()) {
            const std::string& raw = lines_[pos_];
            const std::string data = raw.substr(0, raw.find('#'));
            if (data.find_first_not_of(" \t\v\f") != std::string::npos) return true;
            ++pos_;
        }
        return false;
    }

    // Check a line has exactly `n` tokens.
    void expect_count(const DataLine& dl, size_t n, const std::string& entry,
                      const std::string& what) const {
        if (dl.tokens.size() < n)
            fail(dl.line, dl.tokens.empty() ? 1 : dl.tokens.back().column, entry,
                 "expected " + what + ", found " + std::to_string(dl.tokens.size()) + " value" +
                     (dl.tokens.size() == 1 ? "" : "s"));
        if (dl.tokens.size() > n)
            fail(dl.line, dl.tokens[n].column, entry,
                 "expected " + what + ", found extra text \"" + dl.tokens[n].text +
                     "\" (comments must start with '#')");
    }

    double number(const DataLine& dl, size_t i, const std::string& entry) const {
        const Token& t = dl.tokens[i];
        errno = 0;
        char* end = nullptr;
        const double v = std::strtod(t.text.c_str(), &end);
        if (end == t.text.c_str() || *end != '\0')
            fail(dl.line, t.column, entry, "expected a number, found \"" + t.text + "\"");
        if (!std::isfinite(v) || errno == ERANGE)
            fail(dl.line, t.column, entry, "expected a finite number, found \"" + t.text + "\"");
        return v;
    }

    long long integer(const DataLine& dl, size_t i, const std::string& entry) const {
        const Token& t = dl.tokens[i];
        errno = 0;
        char* end = nullptr;
        const long long v = std::strtoll(t.text.c_str(), &end, 10);
        if (end == t.text.c_str() || *end != '\0') {
            std::string msg = "expected a whole number, found \"" + t.text + "\"";
            if (end != t.text.c_str())
                msg += " (the original MCML would silently read it as " +
                       t.text.substr(0, static_cast<size_t>(end - t.text.c_str())) + ")";
            fail(dl.line, t.column, entry, msg);
        }
        if (errno == ERANGE) fail(dl.line, t.column, entry, "number out of range: " + t.text);
        return v;
    }

  private:
    std::string name_;
    std::vector<std::string> lines_;
    size_t pos_ = 0;
};

}  // namespace

MciFile parse_mci(std::string_view text, const std::string& name, const MciOptions& opt) {
    Reader rd(text, name);
    MciFile file;
    file.path = name;

    rd.next("the file version (e.g. 1.0)");  // skipped, as the original does
    DataLine dl = rd.next("the number of runs");
    rd.expect_count(dl, 1, "number of runs", "1 value (the number of runs)");
    const long long num_runs = rd.integer(dl, 0, "number of runs");
    if (num_runs <= 0 || num_runs > 32767)
        rd.fail(dl.line, dl.tokens[0].column, "number of runs",
                "expected a number of runs in [1, 32767], found " + dl.tokens[0].text);

    std::set<std::string> names;
    for (long long r = 1; r <= num_runs; ++r) {
        const std::string run_tag = "run " + std::to_string(r) + ": ";
        RunSpec run;
        run.source_file = name;

        dl = rd.next("the output file name and format of run " + std::to_string(r));
        run.source_line = dl.line;
        if (dl.tokens.size() > 2)
            rd.expect_count(dl, 2, run_tag + "output file", "a file name and a format (A or B)");
        run.out_name = dl.tokens[0].text;
        if (run.out_name.size() > 255)
            rd.fail(dl.line, dl.tokens[0].column, run_tag + "output file",
                    "file name longer than 255 characters");
        if (dl.tokens.size() == 2) {
            const std::string& f = dl.tokens[1].text;
            if (f != "A" && f != "a" && f != "B" && f != "b")
                rd.fail(dl.line, dl.tokens[1].column, run_tag + "output format",
                        "expected A (ASCII) or B (binary), found \"" + f + "\"");
            run.out_format = static_cast<char>(std::toupper(static_cast<unsigned char>(f[0])));
        }
        if (!names.insert(run.out_name).second)
            rd.fail(dl.line, dl.tokens[0].column, run_tag + "output file",
                    "file name \"" + run.out_name + "\" is used by an earlier run");

        dl = rd.next("the number of photons of run " + std::to_string(r));
        rd.expect_count(dl, 1, run_tag + "No. of photons", "1 value (the number of photons)");
        run.photons = rd.integer(dl, 0, run_tag + "No. of photons");
        if (run.photons <= 0)
            rd.fail(dl.line, dl.tokens[0].column, run_tag + "No. of photons",
                    "expected a positive number of photons, found " + dl.tokens[0].text);

        dl = rd.next("dz and dr of run " + std::to_string(r));
        rd.expect_count(dl, 2, run_tag + "dz, dr", "2 values (dz dr, in cm)");
        run.grid.dz = rd.number(dl, 0, run_tag + "dz");
        run.grid.dr = rd.number(dl, 1, run_tag + "dr");
        if (run.grid.dz <= 0)
            rd.fail(dl.line, dl.tokens[0].column, run_tag + "dz", "expected dz > 0 [cm]");
        if (run.grid.dr <= 0)
            rd.fail(dl.line, dl.tokens[1].column, run_tag + "dr", "expected dr > 0 [cm]");

        dl = rd.next("the numbers of dz, dr, da of run " + std::to_string(r));
        rd.expect_count(dl, 3, run_tag + "No. of dz, dr, da", "3 values (nz nr na)");
        const char* grid_names[3] = {"nz", "nr", "na"};
        int* grid_vals[3] = {&run.grid.nz, &run.grid.nr, &run.grid.na};
        for (size_t k = 0; k < 3; ++k) {
            const long long v = rd.integer(dl, k, run_tag + grid_names[k]);
            if (v <= 0 || v > 100000000)
                rd.fail(dl.line, dl.tokens[k].column, run_tag + grid_names[k],
                        std::string("expected a number of bins in [1, 1e8], found ") +
                            dl.tokens[k].text);
            *grid_vals[k] = static_cast<int>(v);
        }

        dl = rd.next("the number of layers of run " + std::to_string(r));
        rd.expect_count(dl, 1, run_tag + "number of layers", "1 value (the number of layers)");
        const long long nl = rd.integer(dl, 0, run_tag + "number of layers");
        if (nl <= 0 || nl > 10000)
            rd.fail(dl.line, dl.tokens[0].column, run_tag + "number of layers",
                    "expected a number of layers in [1, 10000], found " + dl.tokens[0].text);
        run.layers.resize(static_cast<size_t>(nl) + 2);

        auto ambient = [&](Layer& l, const char* side) {
            const std::string entry = run_tag + "n of the medium " + side;
            DataLine d = rd.next(std::string("the refractive index of the medium ") + side +
                                 " of run " + std::to_string(r));
            rd.expect_count(d, 1, entry, "1 value (the refractive index)");
            l.n = rd.number(d, 0, entry);
            l.source_line = d.line;
            if (l.n <= 0)
                rd.fail(d.line, d.tokens[0].column, entry,
                        "expected a refractive index > 0, found " + d.tokens[0].text);
        };
        ambient(run.layers[0], "above");
        double z = 0.0;
        for (long long i = 1; i <= nl; ++i) {
            const std::string entry = run_tag + "layer " + std::to_string(i);
            DataLine d = rd.next("layer " + std::to_string(i) + " of " + std::to_string(nl) +
                                 " of run " + std::to_string(r) + " (n mua mus g d)");
            rd.expect_count(d, 5, entry, "5 values (n mua mus g d)");
            Layer& l = run.layers[static_cast<size_t>(i)];
            l.source_line = d.line;
            l.n = rd.number(d, 0, entry + " n");
            l.mua = rd.number(d, 1, entry + " mua");
            l.mus = rd.number(d, 2, entry + " mus");
            l.g = rd.number(d, 3, entry + " g");
            const double thick = rd.number(d, 4, entry + " d");
            if (l.n <= 0) rd.fail(d.line, d.tokens[0].column, entry + " n", "expected n > 0");
            if (l.mua < 0)
                rd.fail(d.line, d.tokens[1].column, entry + " mua", "expected mua >= 0 [1/cm]");
            if (l.mus < 0)
                rd.fail(d.line, d.tokens[2].column, entry + " mus", "expected mus >= 0 [1/cm]");
            const double gmin = opt.allow_negative_g ? -1.0 : 0.0;
            if (l.g < gmin || l.g > 1)
                rd.fail(d.line, d.tokens[3].column, entry + " g",
                        opt.allow_negative_g
                            ? "expected -1 <= g <= 1"
                            : "expected 0 <= g <= 1 (the original MCML rejects g < 0; negative "
                              "g needs the default mode)");
            if (thick < 0)
                rd.fail(d.line, d.tokens[4].column, entry + " d", "expected thickness d >= 0 [cm]");
            l.z0 = z;
            z += thick;
            l.z1 = z;
        }
        ambient(run.layers[static_cast<size_t>(nl) + 1], "below");
        compute_critical_angles(run);
        file.runs.push_back(std::move(run));
    }
    if (rd.has_more_data()) {
        DataLine d = rd.next("");
        rd.fail(d.line, d.tokens[0].column, "",
                "unexpected data after the last of the " + std::to_string(num_runs) +
                    " runs the file declares");
    }
    return file;
}

MciFile read_mci(const std::string& path, const MciOptions& opt) {
    std::string text;
    try {
        text = read_file(path);
    } catch (const IoError&) {
        throw InputError({path, 0, 0}, "", "cannot open the .mci file for reading");
    }
    return parse_mci(text, path, opt);
}

std::string format_mci(const std::vector<RunSpec>& runs) {
    std::ostringstream os;
    char buf[512];
    os << "# Written by ssslab. Lengths in cm, mua and mus in 1/cm.\n";
    os << "1.0\t\t\t\t\t\t# file version\n";
    os << runs.size() << "\t\t\t\t\t\t# number of runs\n\n";
    for (const auto& r : runs) {
        os << r.out_name << "\t" << r.out_format << "\t\t\t\t# output filename, ASCII/Binary\n";
        os << r.photons << "\t\t\t\t\t\t# No. of photons\n";
        std::snprintf(buf, sizeof buf, "%.17g\t%.17g\t\t\t\t\t# dz, dr [cm]\n", r.grid.dz,
                      r.grid.dr);
        os << buf;
        os << r.grid.nz << "\t" << r.grid.nr << "\t" << r.grid.na
           << "\t\t\t\t# No. of dz, dr, da\n\n";
        os << r.num_layers() << "\t\t\t\t\t\t# Number of layers\n";
        os << "#n\tmua\tmus\tg\td\t\t# One line for each layer\n";
        std::snprintf(buf, sizeof buf, "%.17g\t\t\t\t\t\t# n for medium above\n", r.layers[0].n);
        os << buf;
        for (int i = 1; i <= r.num_layers(); ++i) {
            const Layer& l = r.layers[static_cast<size_t>(i)];
            std::snprintf(buf, sizeof buf, "%.17g\t%.17g\t%.17g\t%.17g\t%.17g\t# layer %d\n", l.n,
                          l.mua, l.mus, l.g, l.thickness_cm(), i);
            os << buf;
        }
        std::snprintf(buf, sizeof buf, "%.17g\t\t\t\t\t\t# n for medium below\n\n",
                      r.layers.back().n);
        os << buf;
    }
    return os.str();
}

}  // namespace ssslab::mcml
