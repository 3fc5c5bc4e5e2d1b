// Reader for MCML's .mci input files (MCML 1.2.2 manual, "Input data file").
//
// Layout: file version, number of runs, then per run: output file name and format (A/B), number
// of photons, dz dr [cm], nz nr na, number of layers, n of the medium above, one line
// "n mua mus g d" per layer, n of the medium below. Anything after '#' is a comment; blank and
// comment lines are skipped. Unlike the original, CRLF line ends are accepted (the original
// treats "\r\n" as a data line), and every malformed entry is an InputError naming file, line,
// column and entry; the original silently reads "1e6" photons as 1 and ignores stray text.
#pragma once

#include "mcml/run_spec.h"

#include <string>
#include <string_view>
#include <vector>

namespace ssslab::mcml {

struct MciOptions {
    /// Accept g in [-1, 0) (an ssslab extension; the original rejects g < 0).
    bool allow_negative_g = true;
};

struct MciFile {
    std::string path;
    std::vector<RunSpec> runs;
};

/// Parse and validate an .mci file. Throws InputError (malformed) with file:line:column.
MciFile read_mci(const std::string& path, const MciOptions& options = {});
/// Parse .mci text; `name` is used as the file name in messages and in RunSpec::source_file.
MciFile parse_mci(std::string_view text, const std::string& name, const MciOptions& options = {});

/// Write a run back as .mci text (the layout of the original template).
std::string format_mci(const std::vector<RunSpec>& runs);

}  // namespace ssslab::mcml
