// What produced a result: code revision, build, library versions, date, command line, seed.
// Written beside every output together with the fully resolved configuration (Tungsten's toJson
// round trip): a result nobody can reproduce is not a result.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace ssslab {

/// `git describe --always --dirty` of the source tree at build time.
const char* git_revision();

/// Key/value pairs: ssslab version, git revision, build type, compiler, library versions,
/// optional parts, host threads, UTC date, and the command line (if given).
std::vector<std::pair<std::string, std::string>> provenance(const std::string& command_line = {});

/// Multi-line human-readable version report (for `ssslab --version`).
std::string version_report();

/// Current UTC time as ISO 8601.
std::string utc_now();

}  // namespace ssslab
