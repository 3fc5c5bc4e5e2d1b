#include "core/provenance.h"

#include "core/build_info.h"
#include "core/distributed.h"

#include <fmt/core.h>
#include <oneapi/tbb/version.h>
#include <toml++/toml.h>
#include <CLI/Version.hpp>

#include <ctime>
#include <thread>

namespace ssslab {

std::string utc_now() {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

std::vector<std::pair<std::string, std::string>> provenance(const std::string& command_line) {
    std::vector<std::pair<std::string, std::string>> p = {
        {"ssslab_version", SSSLAB_VERSION},
        {"git_revision", git_revision()},
        {"build_type", SSSLAB_BUILD_TYPE},
        {"compiler", SSSLAB_COMPILER},
        {"oneTBB", TBB_VERSION_STRING},
        {"fmt", std::to_string(FMT_VERSION / 10000) + "." +
                    std::to_string(FMT_VERSION / 100 % 100) + "." +
                    std::to_string(FMT_VERSION % 100)},
        {"tomlplusplus", std::to_string(TOML_LIB_MAJOR) + "." + std::to_string(TOML_LIB_MINOR) +
                             "." + std::to_string(TOML_LIB_PATCH)},
        {"CLI11", CLI11_VERSION},
        {"Random123", "Philox4x32-10"},
        {"host_threads", std::to_string(std::thread::hardware_concurrency())},
        {"mpi_ranks", std::to_string(dist::size())},  // core/distributed.h
        {"date_utc", utc_now()},
    };
    if (std::string(SSSLAB_SANITIZE_FLAGS).size()) p.push_back({"sanitize", SSSLAB_SANITIZE_FLAGS});
    if (!command_line.empty()) p.push_back({"command_line", command_line});
    return p;
}

std::string version_report() {
    std::string s = std::string("ssslab ") + SSSLAB_VERSION + " (" + git_revision() + ", " +
                    SSSLAB_BUILD_TYPE + ", " + SSSLAB_COMPILER + ")\n";
    for (const auto& [k, v] : provenance())
        if (k != "date_utc" && k != "ssslab_version" && k != "git_revision")
            s += "  " + k + ": " + v + "\n";
    s += std::string("  optional parts: OpenVDB ") + (SSSLAB_HAVE_OPENVDB ? "yes" : "no") +
         ", OpenGL " +
         (SSSLAB_HAVE_GL ? std::string("yes (") + SSSLAB_GL_PLATFORMS + ")" : std::string("no")) +
         ", MPI " + (SSSLAB_HAVE_MPI ? "yes" : "no") + "\n";
    return s;
}

}  // namespace ssslab
