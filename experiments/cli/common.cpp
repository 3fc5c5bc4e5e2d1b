#include "experiments/cli/common.h"

#include <unistd.h>
#include <cmath>
#include <csignal>
#include <cstdio>

namespace ssslab::cli {

namespace {
// The one mutable global: a signal handler can reach nothing else.
std::atomic<bool> g_interrupted{false};
std::string g_command_line;

extern "C" void on_signal(int sig) {
    if (g_interrupted.exchange(true)) {
        std::signal(sig, SIG_DFL);
        std::raise(sig);
        return;
    }
    const char msg[] =
        "\nssslab: interrupted; finishing the batches in flight and saving a "
        "checkpoint (press again to abort)\n";
    (void)!::write(STDERR_FILENO, msg, sizeof msg - 1);
}
}  // namespace

const std::atomic<bool>* install_interrupt_handler() {
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    return &g_interrupted;
}

void set_command_line(int argc, char** argv) {
    g_command_line.clear();
    for (int i = 0; i < argc; ++i) {
        if (i) g_command_line += ' ';
        g_command_line += argv[i];
    }
}

std::string command_line() {
    return g_command_line;
}

std::string pm(double value, double se) {
    char buf[96];
    if (se > 0 && std::isfinite(se) && value != 0) {
        // Two significant digits of the standard error.
        const int digits = std::max(0, 1 - static_cast<int>(std::floor(std::log10(se))));
        std::snprintf(buf, sizeof buf, "%.*f +- %.*f", digits, value, digits, se);
    } else {
        std::snprintf(buf, sizeof buf, "%.6g", value);
    }
    return buf;
}

void add_common_options(CLI::App& app, CommonOptions& o, const std::string& out_help) {
    app.add_option("--seed", o.seed, "Seed of the counter-based random streams (default 1)");
    app.add_option("--threads", o.threads,
                   "Worker threads (default: all); results do not depend on it")
        ->check(CLI::NonNegativeNumber);
    app.add_option("--out", o.out, out_help);
    app.add_option("--photons", o.photons, "Photon budget (per run or per channel)")
        ->check(CLI::PositiveNumber);
    app.add_option("--time", o.seconds, "Wall-time budget in seconds (per run or per channel)")
        ->check(CLI::PositiveNumber);
    app.add_option("--rel-error", o.rel_error,
                   "Stop when the relative standard error of the total diffuse reflectance "
                   "(or of the transmittance, if larger) falls below this")
        ->check(CLI::Range(1e-9, 1.0));
    app.add_option("--batch", o.batch,
                   "Photons per batch (default: from the photon budget; part of what determines "
                   "the result)")
        ->check(CLI::PositiveNumber);
    app.add_flag("-q,--quiet", o.quiet, "Print nothing but errors");
}

mcml::Budget budget_from(const CommonOptions& o) {
    mcml::Budget b;
    b.photons = o.photons;
    b.seconds = o.seconds;
    b.rel_error = o.rel_error;
    return b;
}

}  // namespace ssslab::cli
