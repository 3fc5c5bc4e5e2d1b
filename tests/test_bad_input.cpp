// Bad input: every malformed .mci file, TOML config and command line in the tables below must be
// refused with exit code 2 and a message on stderr that names the file and line (and column where
// known), the key and what was expected, and shows the offending line; and it must leave no
// output behind (no .mco, .csv, .toml, checkpoint or temporary file), nor anything on stdout.
// A few well-formed inputs are positive controls: they must run and write their outputs, which
// also shows that the templates the bad cases are edited from are valid.
#include "testing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace ssslab {
namespace {

struct BadInputCase {
    std::string name;               ///< test name suffix
    std::string file;               ///< input file written into a fresh directory; empty: none
    std::string content;            ///< its content
    std::vector<std::string> args;  ///< arguments of `ssslab`
    int exit_code;                  ///< expected exit status (2: bad input)
    std::vector<std::string> err;   ///< substrings stderr must contain
    std::vector<std::string> outputs = {};  ///< files the run must write (positive controls only)
    std::vector<std::string> absent = {};   ///< substrings stderr must not contain
};

void PrintTo(const BadInputCase& c, std::ostream* os) {
    *os << c.name;
}

// ---------------------------------------------------------------------------------------------
// .mci inputs

// A valid .mci file of `runs` runs, one entry per line and no blank lines, so that line numbers
// are easy to follow: line 1 file version, 2 number of runs, then 8 lines per run r, from
// 3 + 8 (r - 1): output file "out<r>.mco", photons, dz dr, nz nr na, number of layers, n above,
// layer 1, n below. Run 1 thus has its photons on line 4, its layer on line 9, n below on line 10;
// run 2 has its output file on line 11 and its layer on line 17.
std::vector<std::string> mci_lines(int runs) {
    std::vector<std::string> l = {"1.0      # file version",
                                  std::to_string(runs) + "        # number of runs"};
    for (int r = 1; r <= runs; ++r) {
        l.push_back("out" + std::to_string(r) + ".mco A   # output file name, ASCII");
        l.push_back("100      # No. of photons");
        l.push_back("0.01 0.01    # dz, dr [cm]");
        l.push_back("10 10 10     # No. of dz, dr, da");
        l.push_back("1        # Number of layers");
        l.push_back("1.0      # n for medium above");
        l.push_back("1.37 1 100 0.9 0.1   # layer 1");
        l.push_back("1.0      # n for medium below");
    }
    return l;
}

struct MciEdit {
    std::map<int, std::string> lines = {};  ///< line (from 1) -> new text ("\n" inserts lines)
    int runs = 1;
    int keep = 0;  ///< keep only the first `keep` lines (0: all)
    std::string eol = "\n";
};

std::string mci(const MciEdit& e = {}) {
    std::vector<std::string> l = mci_lines(e.runs);
    for (const auto& [line, text] : e.lines) l.at(static_cast<size_t>(line - 1)) = text;
    if (e.keep > 0) l.resize(static_cast<size_t>(e.keep));
    std::string s;
    for (const auto& x : l) s += x + e.eol;
    return s;
}

std::vector<std::string> mcml(const std::string& file, std::vector<std::string> extra = {}) {
    std::vector<std::string> a = {"mcml", file};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
}

const std::vector<std::string> kCompat = {"--compat", "mcml-1.2.2", "--idum", "1"};

std::vector<std::string> mco_outputs(int runs) {
    std::vector<std::string> o;
    for (int r = 1; r <= runs; ++r) {
        const std::string base = "out" + std::to_string(r);
        o.insert(o.end(), {base + ".mco", base + ".mco.toml", base + "_stderr.mco"});
    }
    return o;
}

std::vector<BadInputCase> mci_cases() {
    const std::string B = "bad.mci";
    return {
        // Positive controls: the templates are valid.
        {"mci_valid_one_run", "good.mci", mci(), mcml("good.mci"), 0, {}, mco_outputs(1)},
        {"mci_valid_two_runs",
         "good.mci",
         mci({.runs = 2}),
         mcml("good.mci"),
         0,
         {},
         mco_outputs(2)},
        // CRLF line endings: the original mishandles them; they must work.
        {"mci_valid_crlf",
         "good.mci",
         mci({.eol = "\r\n"}),
         mcml("good.mci"),
         0,
         {},
         mco_outputs(1)},
        // g < 0 is accepted in the default mode (and rejected in --compat mode below).
        {"mci_negative_g_default_mode",
         "good.mci",
         mci({.lines = {{9, "1.37 1 100 -0.5 0.1  # layer 1"}}}),
         mcml("good.mci"),
         0,
         {},
         mco_outputs(1)},

        // File structure.
        {"mci_empty_file",
         B,
         "",
         mcml(B),
         2,
         {"bad.mci:1: error:", "unexpected end of file", "expected the file version"}},
        {"mci_only_comments",
         B,
         "# ssslab test input\n# nothing else\n",
         mcml(B),
         2,
         {"bad.mci:2: error:", "unexpected end of file", "expected the file version",
          "# nothing else"}},
        {"mci_missing_n_below",
         B,
         mci({.keep = 9}),
         mcml(B),
         2,
         {"bad.mci:9: error:", "unexpected end of file",
          "expected the refractive index of the medium below"}},
        {"mci_trailing_data",
         B,
         mci() + "0.5      # stray line\n",
         mcml(B),
         2,
         {"bad.mci:11:1: error:", "unexpected data after the last of the 1 runs the file declares",
          "0.5      # stray line"}},
        {"mci_non_ascii_byte",
         B,
         mci({.lines = {{9, "1.37 1 100 0.9 0.1\xc2\xa0# layer 1"}}}),
         mcml(B),
         2,
         {"bad.mci:9:19: error:", "non-ASCII byte in an .mci file"}},
        {"mci_control_character",
         B,
         mci({.lines = {{9, "1.37 1 100 0.9 0.1\x01  # layer 1"}}}),
         mcml(B),
         2,
         {"bad.mci:9:19: error:", "control character in an .mci file"}},
        {"mci_crlf_malformed",
         B,
         mci({.lines = {{9, "1.37 1 100 0.9       # layer 1"}}, .eol = "\r\n"}),
         mcml(B),
         2,
         {"bad.mci:9:12: error:", "key 'run 1: layer 1'", "found 4 values",
          "\n    1.37 1 100 0.9       # layer 1\n"},
         {},
         {"\r"}},

        // Number of runs.
        {"mci_runs_not_a_number",
         B,
         mci({.lines = {{2, "two      # number of runs"}}}),
         mcml(B),
         2,
         {"bad.mci:2:1: error:", "key 'number of runs'", "expected a whole number, found \"two\"",
          "two      # number of runs"}},
        {"mci_runs_zero",
         B,
         mci({.lines = {{2, "0        # number of runs"}}}),
         mcml(B),
         2,
         {"bad.mci:2:1: error:", "key 'number of runs'",
          "expected a number of runs in [1, 32767], found 0", "0        # number of runs"}},

        // Output file.
        {"mci_output_format_letter",
         B,
         mci({.lines = {{3, "out1.mco X   # output file name, ASCII"}}}),
         mcml(B),
         2,
         {"bad.mci:3:10: error:", "key 'run 1: output format'",
          "expected A (ASCII) or B (binary), found \"X\"", "out1.mco X   # output file name"}},
        {"mci_duplicate_output_name",
         B,
         mci({.lines = {{11, "out1.mco A   # output file name, ASCII"}}, .runs = 2}),
         mcml(B),
         2,
         {"bad.mci:11:1: error:", "key 'run 2: output file'",
          "file name \"out1.mco\" is used by an earlier run"}},

        // Photons.
        {"mci_photons_float",
         B,
         mci({.lines = {{4, "1e6      # No. of photons"}}}),
         mcml(B),
         2,
         {"bad.mci:4:1: error:", "key 'run 1: No. of photons'",
          "expected a whole number, found \"1e6\"",
          "(the original MCML would silently read it as 1)", "1e6      # No. of photons",
          "\n    ^"}},
        {"mci_photons_negative",
         B,
         mci({.lines = {{4, "-100     # No. of photons"}}}),
         mcml(B),
         2,
         {"bad.mci:4:1: error:", "key 'run 1: No. of photons'",
          "expected a positive number of photons, found -100", "-100     # No. of photons"}},
        {"mci_photons_text",
         B,
         mci({.lines = {{4, "abc      # No. of photons"}}}),
         mcml(B),
         2,
         {"bad.mci:4:1: error:", "key 'run 1: No. of photons'",
          "expected a whole number, found \"abc\"", "abc      # No. of photons"},
         {},
         {"silently"}},
        {"mci_photons_overflow",
         B,
         mci({.lines = {{4, "99999999999999999999  # No. of photons"}}}),
         mcml(B),
         2,
         {"bad.mci:4:1: error:", "key 'run 1: No. of photons'",
          "number out of range: 99999999999999999999"}},

        // Grid.
        {"mci_dz_zero",
         B,
         mci({.lines = {{5, "0 0.01       # dz, dr [cm]"}}}),
         mcml(B),
         2,
         {"bad.mci:5:1: error:", "key 'run 1: dz'", "expected dz > 0 [cm]",
          "0 0.01       # dz, dr [cm]"}},
        {"mci_dr_negative",
         B,
         mci({.lines = {{5, "0.01 -0.01   # dz, dr [cm]"}}}),
         mcml(B),
         2,
         {"bad.mci:5:6: error:", "key 'run 1: dr'", "expected dr > 0 [cm]",
          "0.01 -0.01   # dz, dr [cm]", "\n         ^"}},
        {"mci_dr_nan",
         B,
         mci({.lines = {{5, "0.01 nan     # dz, dr [cm]"}}}),
         mcml(B),
         2,
         {"bad.mci:5:6: error:", "key 'run 1: dr'", "expected a finite number, found \"nan\""}},
        {"mci_grid_two_values",
         B,
         mci({.lines = {{6, "10 10        # No. of dz, dr, da"}}}),
         mcml(B),
         2,
         {"bad.mci:6:4: error:", "key 'run 1: No. of dz, dr, da'",
          "expected 3 values (nz nr na), found 2 values", "10 10        # No. of dz, dr, da"}},
        {"mci_nr_zero",
         B,
         mci({.lines = {{6, "10 0 10      # No. of dz, dr, da"}}}),
         mcml(B),
         2,
         {"bad.mci:6:4: error:", "key 'run 1: nr'",
          "expected a number of bins in [1, 1e8], found 0", "10 0 10      # No. of dz, dr, da"}},
        {"mci_nz_not_integer",
         B,
         mci({.lines = {{6, "10.5 10 10   # No. of dz, dr, da"}}}),
         mcml(B),
         2,
         {"bad.mci:6:1: error:", "key 'run 1: nz'", "expected a whole number, found \"10.5\"",
          "(the original MCML would silently read it as 10)"}},

        // Layers.
        {"mci_layers_zero",
         B,
         mci({.lines = {{7, "0        # Number of layers"}}}),
         mcml(B),
         2,
         {"bad.mci:7:1: error:", "key 'run 1: number of layers'",
          "expected a number of layers in [1, 10000], found 0", "0        # Number of layers"}},
        {"mci_n_above_zero",
         B,
         mci({.lines = {{8, "0        # n for medium above"}}}),
         mcml(B),
         2,
         {"bad.mci:8:1: error:", "key 'run 1: n of the medium above'",
          "expected a refractive index > 0, found 0"}},
        {"mci_layer_four_values",
         B,
         mci({.lines = {{9, "1.37 1 100 0.9       # layer 1"}}}),
         mcml(B),
         2,
         {"bad.mci:9:12: error:", "key 'run 1: layer 1'",
          "expected 5 values (n mua mus g d), found 4 values", "1.37 1 100 0.9       # layer 1"}},
        {"mci_layer_six_values",
         B,
         mci({.lines = {{9, "1.37 1 100 0.9 0.1 layer 1"}}}),
         mcml(B),
         2,
         {"bad.mci:9:20: error:", "key 'run 1: layer 1'",
          "found extra text \"layer\" (comments must start with '#')",
          "1.37 1 100 0.9 0.1 layer 1"}},
        {"mci_layer_n_zero",
         B,
         mci({.lines = {{9, "0 1 100 0.9 0.1      # layer 1"}}}),
         mcml(B),
         2,
         {"bad.mci:9:1: error:", "key 'run 1: layer 1 n'", "expected n > 0"}},
        {"mci_mua_negative",
         B,
         mci({.lines = {{9, "1.37 -1 100 0.9 0.1  # layer 1"}}}),
         mcml(B),
         2,
         {"bad.mci:9:6: error:", "key 'run 1: layer 1 mua'", "expected mua >= 0 [1/cm]",
          "1.37 -1 100 0.9 0.1  # layer 1"}},
        {"mci_g_above_one",
         B,
         mci({.lines = {{9, "1.37 1 100 1.5 0.1   # layer 1"}}}),
         mcml(B),
         2,
         {"bad.mci:9:12: error:", "key 'run 1: layer 1 g'", "expected -1 <= g <= 1",
          "1.37 1 100 1.5 0.1   # layer 1"}},
        {"mci_negative_g_compat_mode",
         B,
         mci({.lines = {{9, "1.37 1 100 -0.5 0.1  # layer 1"}}}),
         mcml(B, kCompat),
         2,
         {"bad.mci:9:12: error:", "key 'run 1: layer 1 g'", "expected 0 <= g <= 1",
          "the original MCML rejects g < 0", "1.37 1 100 -0.5 0.1  # layer 1"}},
        {"mci_thickness_negative",
         B,
         mci({.lines = {{9, "1.37 1 100 0.9 -0.1  # layer 1"}}}),
         mcml(B),
         2,
         {"bad.mci:9:16: error:", "key 'run 1: layer 1 d'", "expected thickness d >= 0 [cm]",
          "1.37 1 100 0.9 -0.1  # layer 1"}},

        // Well-formed but infeasible runs, refused before any work starts.
        {"mci_mua_zero_infinite_layer",
         B,
         mci({.lines = {{9, "1.37 0 100 0.9 1e8   # layer 1"}}}),
         mcml(B),
         2,
         {"error: bad.mci:9: ", "layer 1 has mua = 0", "1e+08 cm thick",
          "Give the layer a positive mua or a finite thickness"}},
        {"mci_glass_only_layer",
         B,
         mci({.lines = {{9, "1.37 0 0 0.9 0.1     # layer 1"}}}),
         mcml(B),
         2,
         {"error: bad.mci:9: ", "layer 1 is glass (mua = mus = 0) and is the only layer"}},
        {"mci_all_layers_glass",
         B,
         mci({.lines = {{7, "2        # Number of layers"},
                        {9, "1.37 0 0 0.9 0.1     # layer 1\n1.5 0 0 0 0.1        # layer 2"}}}),
         mcml(B),
         2,
         {"error: bad.mci:9: ", "every layer is glass (mua = mus = 0)"}},
        {"mci_albedo_one_thick_layer",
         B,
         mci({.lines = {{9, "1.37 1e-12 100 0.9 1e4  # layer 1"}}}),
         mcml(B),
         2,
         {"error: bad.mci:9: ", "scattering events", "Increase mua or reduce the thickness"}},
        {"mci_grid_too_large",
         B,
         mci({.lines = {{6, "100000 100000 100000  # No. of dz, dr, da"}}}),
         mcml(B),
         2,
         {"error: bad.mci:3: ", "tally cells", "Use fewer bins"}},
        {"mci_grid_beyond_short_compat_mode",
         B,
         mci({.lines = {{6, "10 40000 10  # No. of dz, dr, da"}}}),
         mcml(B, kCompat),
         2,
         {"error: bad.mci:3: ", "grid sizes above 32767"}},

        // A bad run 2 leaves no output of run 1 either: all runs are checked before any runs.
        {"mci_run2_malformed",
         B,
         mci({.lines = {{17, "1.37 1 100 0.9       # layer 1"}}, .runs = 2}),
         mcml(B),
         2,
         {"bad.mci:17:12: error:", "key 'run 2: layer 1'", "found 4 values"}},
        {"mci_run2_infeasible",
         B,
         mci({.lines = {{17, "1.37 0 100 0.9 1e8   # layer 1"}}, .runs = 2}),
         mcml(B),
         2,
         {"error: bad.mci:17: ", "layer 1 has mua = 0"}},

        // File and command line.
        {"mci_nonexistent_file",
         "",
         "",
         mcml("missing.mci"),
         2,
         {"missing.mci: error:", "cannot open the .mci file for reading"}},
        {"mci_compat_unknown_target",
         B,
         mci(),
         mcml(B, {"--compat", "mcml-1.3"}),
         2,
         {"<command line>: error: key '--compat'", "unknown compatibility target \"mcml-1.3\"",
          "the only one is \"mcml-1.2.2\""}},
        {"mci_idum_without_compat",
         B,
         mci(),
         mcml(B, {"--idum", "5"}),
         2,
         {"<command line>: error: key '--idum'", "needs --compat mcml-1.2.2"}},
        {"mci_seed_with_compat",
         B,
         mci(),
         mcml(B, {"--compat", "mcml-1.2.2", "--seed", "3"}),
         2,
         {"<command line>: error: key '--seed'", "seed it with --idum"}},
    };
}

// ---------------------------------------------------------------------------------------------
// TOML configs of `ssslab profile`

std::vector<std::string> profile(std::vector<std::string> extra = {}) {
    std::vector<std::string> a = {"profile", "--config", "cfg.toml", "--photons",
                                  "100",     "--out",    "prof.csv"};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
}

// Lines 2 and 3 of a [material] table with explicit coefficients (Skin1 in 1/mm).
const std::string kSigmas =
    "sigma_a_per_mm = [0.032, 0.17, 0.48]\n"
    "sigma_s_per_mm = [0.74, 0.88, 1.01]\n";

std::vector<BadInputCase> toml_cases() {
    const std::string C = "cfg.toml";
    const std::string skin1 = "[material]\npreset = \"Skin1\"\n";
    const std::vector<std::string> csv = {"prof.csv", "prof.csv.toml"};
    return {
        // Positive controls: the templates are valid.
        {"toml_valid_preset", C, skin1, profile(), 0, {}, csv},
        {"toml_valid_explicit",
         C,
         "[material]\n" + kSigmas + "eta = 1.3\ng = 0.9\n",
         profile(),
         0,
         {},
         csv},

        // Syntax.
        {"toml_syntax_error",
         C,
         skin1 + "eta_above = 1.0 1.2\n",
         profile(),
         2,
         {"cfg.toml:3:17: error: TOML syntax error", "eta_above = 1.0 1.2"}},
        {"toml_duplicate_key",
         C,
         skin1 + "eta_above = 1.0\neta_above = 1.2\n",
         profile(),
         2,
         {"cfg.toml:4:13: error: TOML syntax error", "eta_above", "\n    eta_above = 1.2\n"}},

        // Unknown and misspelled keys and tables.
        {"toml_unknown_top_level_key",
         C,
         "seed = 3\ncolour = \"red\"\n" + skin1,
         profile(),
         2,
         {"cfg.toml:2:1: error: key 'colour': unknown key",
          "valid keys here:", "colour = \"red\""}},
        {"toml_unknown_table",
         C,
         skin1 + "[colour]\nred = 1\n",
         profile(),
         2,
         {"cfg.toml:3:2: error: key 'colour': unknown key", "\n    [colour]\n"}},
        // A misspelled *required* key: the error names the misspelling where it is, not only
        // the missing key at the table header.
        {"toml_misspelled_required_key",
         C,
         "[material]\nsigma_a_per_mn = [0.032, 0.17, 0.48]\nsigma_s_per_mm = [0.74, 0.88, 1.01]\n"
         "eta = 1.3\n",
         profile(),
         2,
         {"cfg.toml:2:1: error: key 'material.sigma_a_per_mn'", "did you mean 'sigma_a_per_mm'",
          "sigma_a_per_mn = [0.032, 0.17, 0.48]"}},
        {"toml_misspelled_optional_key",
         C,
         skin1 + "eta_abvoe = 1.0\n",
         profile(),
         2,
         {"cfg.toml:3:1: error: key 'material.eta_abvoe': unknown key",
          "(did you mean 'eta_above'?)", "valid keys here:", "eta_abvoe = 1.0"}},
        {"toml_misspelled_grid_key",
         C,
         skin1 + "[grid]\ndr_nm = 0.1\n",
         profile(),
         2,
         {"cfg.toml:4:1: error: key 'grid.dr_nm': unknown key", "(did you mean 'dr_mm'?)",
          "dr_nm = 0.1"}},
        {"toml_crlf_misspelled_key",
         C,
         "[material]\r\npreset = \"Skin1\"\r\neta_abvoe = 1.0\r\n",
         profile(),
         2,
         {"cfg.toml:3:1: error: key 'material.eta_abvoe'", "\n    eta_abvoe = 1.0\n"},
         {},
         {"\r"}},

        // Types.
        {"toml_wrong_type_string",
         C,
         "[material]\n" + kSigmas + "eta = \"1.3\"\n",
         profile(),
         2,
         {"cfg.toml:4:7: error: key 'material.eta': expected a number, got a string",
          "eta = \"1.3\""}},
        {"toml_rgb_two_numbers",
         C,
         "[material]\nsigma_a_per_mm = [0.032, 0.17]\nsigma_s_per_mm = [0.74, 0.88, 1.01]\n"
         "eta = 1.3\n",
         profile(),
         2,
         {"cfg.toml:2:18: error: key 'material.sigma_a_per_mm'",
          "expected 3 numbers [R, G, B], got an array of 2", "sigma_a_per_mm = [0.032, 0.17]"}},
        {"toml_rgb_with_string",
         C,
         "[material]\n" + kSigmas + "eta = 1.3\ng = [0.9, 0.9, \"x\"]\n",
         profile(),
         2,
         {"cfg.toml:5:16: error: key 'material.g': expected a number, got a string",
          "g = [0.9, 0.9, \"x\"]"}},
        {"toml_table_expected",
         C,
         "grid = 5\n" + skin1,
         profile(),
         2,
         {"cfg.toml:1:8: error: key 'grid': expected a table, got an integer", "grid = 5"}},
        {"toml_seed_string",
         C,
         "seed = \"x\"\n" + skin1,
         profile(),
         2,
         {"cfg.toml:1:8: error: key 'seed': expected an integer, got a string", "seed = \"x\""}},
        {"toml_nr_fraction",
         C,
         skin1 + "[grid]\nnr = 2.5\n",
         profile(),
         2,
         {"cfg.toml:4:6: error: key 'grid.nr'",
          "expected an integer, got a number with a fractional part", "nr = 2.5"}},

        // Ranges.
        {"toml_g_out_of_range",
         C,
         "[material]\n" + kSigmas + "eta = 1.3\ng = 2\n",
         profile(),
         2,
         {"cfg.toml:5:5: error: key 'material.g': expected a number in [-1, 1], got 2",
          "\n    g = 2\n        ^"}},
        {"toml_negative_sigma",
         C,
         "[material]\nsigma_a_per_mm = [0.032, 0.17, 0.48]\nsigma_s_per_mm = [0.74, -0.88, 1.01]\n"
         "eta = 1.3\n",
         profile(),
         2,
         {"cfg.toml:3:25: error: key 'material.sigma_s_per_mm'",
          "expected a number in [0, inf), got -0.88", "sigma_s_per_mm = [0.74, -0.88, 1.01]"}},
        {"toml_eta_nan",
         C,
         "[material]\n" + kSigmas + "eta = nan\n",
         profile(),
         2,
         {"cfg.toml:4:7: error: key 'material.eta': expected a finite number", "eta = nan"}},
        {"toml_thickness_zero",
         C,
         skin1 + "thickness_mm = 0\n",
         profile(),
         2,
         {"cfg.toml:3:16: error: key 'material.thickness_mm'",
          "expected a number in (0, inf), got 0", "thickness_mm = 0"}},
        {"toml_nr_zero",
         C,
         skin1 + "[grid]\nnr = 0\n",
         profile(),
         2,
         {"cfg.toml:4:6: error: key 'grid.nr'", "expected an integer in [1, 1e+07], got 0",
          "nr = 0"}},
        {"toml_rel_error_above_one",
         C,
         skin1 + "[budget]\nrel_error = 2\n",
         profile(),
         2,
         {"cfg.toml:4:13: error: key 'budget.rel_error'", "expected a number in (0, 1), got 2",
          "rel_error = 2"}},
        {"toml_photons_negative",
         C,
         skin1 + "[budget]\nphotons = -5\n",
         profile(),
         2,
         {"cfg.toml:4:11: error: key 'budget.photons'", "expected an integer in [1, 9e+18], got -5",
          "photons = -5"}},
        // 1e30 is a whole number beyond the range: the message gives the range.
        {"toml_photons_too_large",
         C,
         skin1 + "[budget]\nphotons = 1e30\n",
         profile(),
         2,
         {"cfg.toml:4:11: error: key 'budget.photons'", "[1, 9e+18]", "photons = 1e30"},
         {},
         {"fractional part"}},
        {"toml_seconds_negative",
         C,
         skin1 + "[budget]\nseconds = -1\n",
         profile(),
         2,
         {"cfg.toml:4:11: error: key 'budget.seconds'", "expected a number in (0, inf), got -1",
          "seconds = -1"}},
        {"toml_unit_inch",
         C,
         skin1 + "[output]\nunit = \"inch\"\n",
         profile(),
         2,
         {"cfg.toml:4:8: error: key 'output.unit'", "expected one of \"mm\", \"cm\", got \"inch\"",
          "unit = \"inch\""}},

        // Conflicting, missing and unknown material descriptions.
        {"toml_sigma_per_mm_and_per_cm",
         C,
         "[material]\n" + kSigmas + "sigma_a_per_cm = [0.32, 1.7, 4.8]\neta = 1.3\n",
         profile(),
         2,
         {"cfg.toml:4:18: error: key 'material.sigma_a_per_cm'",
          "give sigma_a once, per mm or per cm, not both", "sigma_a_per_cm = [0.32, 1.7, 4.8]"}},
        {"toml_thickness_mm_and_cm",
         C,
         skin1 + "thickness_mm = 2\nthickness_cm = 0.2\n",
         profile(),
         2,
         {"cfg.toml:4:16: error: key 'material.thickness_cm'",
          "give thickness once, in mm or in cm, not both"}},
        {"toml_dr_mm_and_cm",
         C,
         skin1 + "[grid]\ndr_mm = 0.1\ndr_cm = 0.01\n",
         profile(),
         2,
         {"cfg.toml:5:9: error: key 'grid.dr_cm'", "give dr once, in mm or in cm, not both"}},
        {"toml_unknown_preset",
         C,
         "[material]\npreset = \"Skin3\"\n",
         profile(),
         2,
         {"cfg.toml:2:10: error: key 'material.preset'", "unknown material \"Skin3\"",
          "(did you mean \"Skin1\"?)", "known materials: Apple,", "Wholemilk",
          "preset = \"Skin3\""}},
        {"toml_preset_and_coefficients",
         C,
         skin1 + kSigmas,
         profile(),
         2,
         {"cfg.toml:2:10: error: key 'material.preset'",
          "give either a preset or explicit coefficients, not both"}},
        {"toml_eta_missing",
         C,
         "[material]\n" + kSigmas,
         profile(),
         2,
         {"cfg.toml:1:1: error: key 'material.eta'", "required number is missing", "(0, inf)"}},
        {"toml_missing_material",
         C,
         "[grid]\nnr = 100\n",
         profile(),
         2,
         {"cfg.toml: error: key 'material'", "no material: give --material <name>", "Skin1"}},
        {"toml_material_in_config_and_command_line",
         C,
         skin1,
         profile({"--material", "Skin1"}),
         2,
         {"cfg.toml: error: key '--material'", "either with --material or in [material]"}},
        {"cli_unknown_material",
         "",
         "",
         {"profile", "--material", "Skin3", "--photons", "100", "--out", "prof.csv"},
         2,
         {"<command line>: error: key '--material'", "unknown material \"Skin3\"",
          "did you mean \"Skin1\"", "known materials: Apple,"}},
    };
}

// ---------------------------------------------------------------------------------------------
// Command-line values (checked by CLI11 before any file is read) and files that are not text

// The bytes of a small ELF header: NUL bytes, control characters, invalid UTF-8.
const std::string kBinary = std::string(
                                "\x7f"
                                "ELF\x02\x01\x01\0\0\0\0\0\0\0\0\0\x03\0>\0\x01\0\0\0",
                                24) +
                            "\xff\xfe\x1b[31m\n\x90\x80\0\0\n";
const std::vector<std::string> kRawBytes = {std::string(1, '\0'), "\x7f", "\x1b", "\xff", "\x90"};

std::vector<BadInputCase> cli_cases() {
    const std::string S = "s.toml";  // never read: the command line fails first
    const std::string any = "# not read\n";
    const std::vector<std::string> cli11 = {"not in range", "1797693134862315708", "[Option"};
    return {
        {"cli_render_spp_zero",
         S,
         any,
         {"render", S, "--spp", "0"},
         2,
         {"ssslab render: error: --spp: must be a positive integer, got 0"},
         {},
         cli11},
        {"cli_render_spp_text",
         S,
         any,
         {"render", S, "--spp", "many"},
         2,
         {"ssslab render: error: --spp: must be a positive integer, got 'many'"}},
        {"cli_render_spp_fraction",
         S,
         any,
         {"render", S, "--spp", "1.5"},
         2,
         {"ssslab render: error: --spp: must be a positive integer, got '1.5'"}},
        {"cli_render_width_zero",
         S,
         any,
         {"render", S, "--width", "0"},
         2,
         {"ssslab render: error: --width: must be an integer in [1, 16384], got 0"}},
        {"cli_render_rel_error_above_one",
         S,
         any,
         {"render", S, "--rel-error", "2"},
         2,
         {"ssslab render: error: --rel-error: must be a number in (0, 1), got 2"}},
        {"cli_render_time_negative",
         S,
         any,
         {"render", S, "--time", "-1"},
         2,
         {"ssslab render: error: --time: must be a positive number, got -1"},
         {},
         cli11},
        // render counts samples per pixel: it does not take --photons or --batch at all.
        {"cli_render_photons_not_an_option",
         S,
         any,
         {"render", S, "--photons", "100"},
         2,
         {"ssslab render: error:", "--photons", "Run `ssslab render --help`"}},
        {"cli_render_batch_not_an_option",
         S,
         any,
         {"render", S, "--batch", "3"},
         2,
         {"ssslab render: error:", "--batch"}},
        {"cli_render_missing_scene",
         "",
         "",
         {"render", "missing.toml"},
         2,
         {"ssslab render: error: scene file 'missing.toml' does not exist"},
         {},
         {"scene: scene file", "File does not exist"}},
        {"cli_render_scene_is_a_directory",
         "",
         "",
         {"render", "."},
         2,
         {"ssslab render: error: scene file '.' is a directory, not a file"}},
        {"cli_scene_missing_file",
         "",
         "",
         {"scene", "missing.toml"},
         2,
         {"ssslab scene: error: scene file 'missing.toml' does not exist"}},
        {"cli_render_missing_reference",
         S,
         any,
         {"render", S, "--reference", "ref.exr"},
         2,
         {"ssslab render: error: --reference: reference image 'ref.exr' does not exist"}},
        {"cli_profile_missing_config",
         "",
         "",
         {"profile", "--config", "nope.toml"},
         2,
         {"ssslab profile: error: --config: config file 'nope.toml' does not exist"}},
        {"cli_profile_unit_inch",
         "",
         "",
         {"profile", "-m", "Skin1", "--unit", "inch"},
         2,
         {"ssslab profile: error: --unit: must be one of mm, cm, got 'inch'"}},
        {"cli_profile_engine_misspelt",
         "",
         "",
         {"profile", "-m", "Skin1", "--engine", "volpth"},
         2,
         {"ssslab profile: error: --engine: must be one of mcml, volpath, got 'volpth'",
          "(did you mean 'volpath'?)"}},
        {"cli_profile_threads_negative",
         "",
         "",
         {"profile", "-m", "Skin1", "--threads", "-1"},
         2,
         {"ssslab profile: error: --threads: must be an integer in [0, 65536], got -1"}},
        {"cli_profile_seed_negative",
         "",
         "",
         {"profile", "-m", "Skin1", "--seed", "-3"},
         2,
         {"ssslab profile: error: --seed: must be a non-negative integer, got -3"}},
        {"cli_profile_photons_exponent",
         "",
         "",
         {"profile", "-m", "Skin1", "--photons", "1e6"},
         2,
         {"ssslab profile: error: --photons: must be a positive integer, got '1e6'"}},
        {"cli_profile_photons_overflow",
         "",
         "",
         {"profile", "-m", "Skin1", "--photons", "99999999999999999999"},
         2,
         {"ssslab profile: error: --photons: must be a positive integer, got "
          "99999999999999999999"}},
        {"cli_profile_unknown_option",
         "",
         "",
         {"profile", "-m", "Skin1", "--photon", "100"},
         2,
         {"ssslab profile: error:", "--photon"}},
        {"cli_mcml_batch_zero",
         "good.mci",
         mci(),
         mcml("good.mci", {"--batch", "0"}),
         2,
         {"ssslab mcml: error: --batch: must be a positive integer, got 0"}},
        {"cli_mcml_checkpoint_seconds_zero",
         "good.mci",
         mci(),
         mcml("good.mci", {"--checkpoint-seconds", "0"}),
         2,
         {"ssslab mcml: error: --checkpoint-seconds: must be a positive number, got 0"}},
        {"cli_sphere_rel_error_zero",
         "",
         "",
         {"sphere", "-m", "Skin1", "--rel-error", "0"},
         2,
         {"ssslab sphere: error: --rel-error: must be a number in (0, 1), got 0"}},
        {"cli_compare_missing_image",
         "",
         "",
         {"compare", "--a", "a.exr", "--b", "b.exr"},
         2,
         {"ssslab compare: error: --a: image 'a.exr' does not exist"}},
        {"cli_run_missing_config",
         "",
         "",
         {"run", "nope.toml"},
         2,
         {"ssslab run: error: experiment config 'nope.toml' does not exist"}},
        {"cli_no_such_command", "", "", {"rendr"}, 2, {"ssslab: error:", "rendr"}},

        // A bad item of a list: the column and the caret are the item's, not the list's '['.
        {"toml_list_item_caret",
         "exp.toml",
         "[experiment]\nname = \"small\"\n\n[materials]\npresets = [\"Skin1\", \"Skni2\"]\n\n"
         "[outputs.profiles]\n",
         {"run", "exp.toml", "--dry-run"},
         2,
         {"exp.toml:5:21: error: key 'materials.presets'", "unknown material \"Skni2\"",
          "(did you mean \"Skin2\"?)",
          "\n    presets = [\"Skin1\", \"Skni2\"]\n                        ^\n"}},

        {"toml_sphere_models_item_caret",
         "sph.toml",
         "models = [\"dipole\", \"bogus\"]\n[material]\npreset = \"Skin1\"\n",
         {"sphere", "--config", "sph.toml", "--photons", "100", "--out", "o"},
         2,
         {"sph.toml:1:21: error: key 'models': unknown diffusion model \"bogus\"",
          "\n    models = [\"dipole\", \"bogus\"]\n                        ^"}},

        // Files that are not text: the error names the place but shows none of the bytes.
        {"binary_config",
         "cfg.toml",
         kBinary,
         profile(),
         2,
         {"cfg.toml:1:", "error:", "the line is not shown", "is this a binary file?"},
         {},
         kRawBytes},
        {"binary_scene",
         S,
         kBinary,
         {"scene", S},
         2,
         {"s.toml:1:", "error:", "is this a binary file?"},
         {},
         kRawBytes},
        {"binary_mci",
         "bad.mci",
         kBinary,
         mcml("bad.mci"),
         2,
         {"bad.mci:1", "error:"},
         {},
         kRawBytes},
        // A stray control character (an escape sequence would recolour the terminal).
        {"toml_escape_sequence_in_line",
         "cfg.toml",
         "[material]\npreset = \"Skin1\" \x1b[31m\n",
         profile(),
         2,
         {"cfg.toml:2:", "the line is not shown"},
         {},
         {"\x1b"}},
    };
}

std::vector<BadInputCase> all_cases() {
    std::vector<BadInputCase> v = mci_cases();
    const std::vector<BadInputCase> t = toml_cases();
    v.insert(v.end(), t.begin(), t.end());
    const std::vector<BadInputCase> c = cli_cases();
    v.insert(v.end(), c.begin(), c.end());
    return v;
}

class BadInput : public ::testing::TestWithParam<BadInputCase> {};

TEST_P(BadInput, RefusedWithLocatedMessageAndNoOutput) {
    const BadInputCase& c = GetParam();
    testing::TempDir dir;
    std::vector<std::string> expected_files;
    if (!c.file.empty()) {
        dir.write(c.file, c.content);
        expected_files.push_back(c.file);
    }
    const testing::CommandResult r = testing::run_ssslab(c.args, dir.path());
    SCOPED_TRACE("stderr:\n" + r.err + "\nstdout:\n" + r.out);

    EXPECT_EQ(r.exit_code, c.exit_code);
    for (const auto& s : c.err) EXPECT_NE(r.err.find(s), std::string::npos) << "missing: " << s;
    for (const auto& s : c.absent)
        EXPECT_EQ(r.err.find(s), std::string::npos) << "unexpected: " << s;
    if (c.exit_code != 0) {
        EXPECT_NE(r.err, "");
        EXPECT_EQ(r.out, "") << "an error must not print results";
        EXPECT_EQ(r.err.find("internal error"), std::string::npos);
    }

    // No partial output: only the input is left (positive controls: the input and the outputs).
    expected_files.insert(expected_files.end(), c.outputs.begin(), c.outputs.end());
    std::sort(expected_files.begin(), expected_files.end());
    EXPECT_EQ(dir.files(), expected_files);
}

INSTANTIATE_TEST_SUITE_P(Cases, BadInput, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<BadInputCase>& p) {
                             return p.param.name;
                         });

// The table is as large as the issue asks: at least 20 malformed .mci files and 15 configs.
TEST(BadInputTable, CoversEnoughMalformedFiles) {
    int mci = 0, toml = 0;
    for (const auto& c : all_cases()) {
        if (c.exit_code == 0) continue;
        if (c.file.size() > 4 && c.file.substr(c.file.size() - 4) == ".mci") ++mci;
        if (c.file.size() > 5 && c.file.substr(c.file.size() - 5) == ".toml") ++toml;
    }
    EXPECT_GE(mci, 20);
    EXPECT_GE(toml, 15);
}

}  // namespace
}  // namespace ssslab
