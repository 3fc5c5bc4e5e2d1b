// MCML's .mco output (format "A1"), section for section as MCML 1.2.2's WriteResult() writes it,
// so CONV and existing scripts read it; and a reader for it.
#pragma once

#include "mcml/run_spec.h"
#include "mcml/tally.h"

#include <cstdint>
#include <string>

namespace ssslab::mcml {

/// The .mco text. `photons` is echoed in InParm (the photons actually traced); `user_seconds` goes
/// into the "User time" line (line 10), the only line that differs between identical runs.
std::string format_mco(const RunSpec& run, const McoResult& r, std::int64_t photons,
                       double user_seconds);

/// The parts of an .mco file that tests and tools need.
struct McoFile {
    std::int64_t photons = 0;
    Grid grid;
    int num_layers = 0;
    McoResult result;
};

/// Parse an .mco file written by MCML 1.2.2 or by ssslab. Throws InputError.
McoFile parse_mco(const std::string& text, const std::string& name);
McoFile read_mco(const std::string& path);

}  // namespace ssslab::mcml
