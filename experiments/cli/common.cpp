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

void add_fresh_option(CLI::App& app, bool& fresh) {
    app.add_flag("--fresh", fresh,
                 "Start afresh even if a checkpoint of an earlier run is there (it is replaced). "
                 "Without it a run resumes from a checkpoint of the same input and refuses one of "
                 "other input, saying what differs");
}

mcml::Budget budget_from(const CommonOptions& o) {
    mcml::Budget b;
    b.photons = o.photons;
    b.seconds = o.seconds;
    b.rel_error = o.rel_error;
    return b;
}

void say_resuming(const std::string& command, const std::string& what, double done, double total,
                  const std::string& unit, const std::string& checkpoint, bool quiet) {
    if (quiet) return;
    char d[32], t[32];
    std::snprintf(d, sizeof d, "%.0f", done);
    std::snprintf(t, sizeof t, "%.0f", total);
    std::string line =
        "ssslab " + command + ": " + (what.empty() ? "" : what + ": ") + "resuming from " + d;
    if (total > 0) line += std::string(" of ") + t;
    line += " " + unit + " (checkpoint " + checkpoint + ")\n";
    std::fputs(line.c_str(), stderr);
}

std::string error_figure(const std::string& label, double value, double se) {
    if (!(se > 0) || !(value != 0) || !std::isfinite(se / value)) return "";
    char b[32];
    std::snprintf(b, sizeof b, " %.3g%%", 100.0 * se / std::abs(value));
    return label + b;
}

RunsProgress::RunsProgress(std::string command, std::function<std::string(int)> label, double total,
                           std::string unit, bool quiet)
    : command_(std::move(command)),
      label_(std::move(label)),
      total_(total),
      unit_(std::move(unit)),
      quiet_(quiet) {}

void RunsProgress::start(int run) {
    if (run == current_) return;
    current_ = run;
    progress_.reset();
    if (!quiet_) progress_ = std::make_unique<Progress>(label_(run), total_, unit_);
}

void RunsProgress::batch(int run, double done, double value, double se) {
    start(run);
    if (progress_) progress_->update(done, error_figure("rel.err", value, se));
}

void RunsProgress::resume(int run, double done, const std::string& checkpoint) {
    start(run);
    if (progress_) progress_->resume_from(done);
    say_resuming(command_, label_(run), done, total_, unit_, checkpoint, quiet_);
}

}  // namespace ssslab::cli
