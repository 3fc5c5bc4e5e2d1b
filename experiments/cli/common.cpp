#include "experiments/cli/common.h"

#include "core/error.h"
#include "core/format.h"
#include "core/provenance.h"

#include <unistd.h>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <limits>

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

void add_seed_option(CLI::App& app, CommonOptions& o, const std::string& help) {
    app.add_option("--seed", o.seed, help)->check(nonnegative_integer());
}

void add_threads_option(CLI::App& app, CommonOptions& o, const std::string& help) {
    app.add_option("--threads", o.threads, help)->check(integer_in(0, 65536));
}

void add_out_option(CLI::App& app, CommonOptions& o, const std::string& help) {
    app.add_option("--out", o.out, help);
}

void add_photons_option(CLI::App& app, CommonOptions& o, const std::string& help) {
    app.add_option("--photons", o.photons, help)->check(positive_integer());
}

void add_time_option(CLI::App& app, CommonOptions& o, const std::string& help) {
    app.add_option("--time", o.seconds, help)->check(positive_number());
}

void add_rel_error_option(CLI::App& app, CommonOptions& o, const std::string& help) {
    app.add_option("--rel-error", o.rel_error, help)->check(number_in(0.0, 1.0, true));
}

void add_batch_option(CLI::App& app, CommonOptions& o, const std::string& help) {
    app.add_option("--batch", o.batch, help)->check(positive_integer());
}

void add_quiet_flag(CLI::App& app, CommonOptions& o) {
    app.add_flag("-q,--quiet", o.quiet, "Print nothing but errors");
}

namespace {

// A whole number written in decimal digits (an optional sign), within int64.
std::optional<std::int64_t> parse_integer(const std::string& s) {
    const char* b = s.data();
    const char* e = s.data() + s.size();
    if (b != e && *b == '+') ++b;
    std::int64_t v = 0;
    const auto r = std::from_chars(b, e, v);
    if (r.ec != std::errc() || r.ptr != e || b == e) return std::nullopt;
    return v;
}

bool is_integer_text(const std::string& s) {
    size_t i = (!s.empty() && (s[0] == '+' || s[0] == '-')) ? 1 : 0;
    if (i == s.size()) return false;
    for (; i < s.size(); ++i)
        if (s[i] < '0' || s[i] > '9') return false;
    return true;
}

std::optional<double> parse_number(const std::string& s) {
    const char* b = s.data();
    const char* e = s.data() + s.size();
    if (b != e && *b == '+') ++b;
    double v = 0;
    const auto r = std::from_chars(b, e, v);
    if (r.ec != std::errc() || r.ptr != e || b == e || !std::isfinite(v)) return std::nullopt;
    return v;
}

std::string shown(const std::string& s) {
    return "'" + s + "'";
}

CLI::Validator integer_check(std::int64_t lo, std::int64_t hi, const std::string& what,
                             const std::string& desc) {
    return CLI::Validator(
        [lo, hi, what](std::string& s) -> std::string {
            const auto v = parse_integer(s);
            if (!v) {
                // A whole number beyond int64 is out of range, anything else is not a number.
                if (is_integer_text(s)) return "must be " + what + ", got " + s;
                return "must be " + what + ", got " + shown(s);
            }
            if (*v < lo || *v > hi) return "must be " + what + ", got " + s;
            return {};
        },
        desc);
}

}  // namespace

CLI::Validator integer_in(std::int64_t lo, std::int64_t hi) {
    const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    return integer_check(lo, hi, "an integer in " + range, range);
}

CLI::Validator positive_integer() {
    return integer_check(1, std::numeric_limits<std::int64_t>::max(), "a positive integer",
                         "POSITIVE");
}

CLI::Validator nonnegative_integer() {
    return integer_check(0, std::numeric_limits<std::int64_t>::max(), "a non-negative integer",
                         "NONNEGATIVE");
}

CLI::Validator number_in(double lo, double hi, bool open) {
    const std::string range = std::string(open ? "(" : "[") + format_g(lo, 6) + ", " +
                              format_g(hi, 6) + (open ? ")" : "]");
    const std::string what = "a number in " + range;
    return CLI::Validator(
        [lo, hi, open, what](std::string& s) -> std::string {
            const auto v = parse_number(s);
            if (!v) return "must be " + what + ", got " + shown(s);
            if (open ? !(*v > lo && *v < hi) : !(*v >= lo && *v <= hi))
                return "must be " + what + ", got " + s;
            return {};
        },
        range);
}

CLI::Validator positive_number() {
    return CLI::Validator(
        [](std::string& s) -> std::string {
            const auto v = parse_number(s);
            if (!v) return "must be a positive number, got " + shown(s);
            if (!(*v > 0)) return "must be a positive number, got " + s;
            return {};
        },
        "POSITIVE");
}

CLI::Validator one_of(std::vector<std::string> choices) {
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
    return CLI::Validator(
        [choices, list](std::string& s) -> std::string {
            if (std::find(choices.begin(), choices.end(), s) != choices.end()) return {};
            std::string msg = "must be one of " + list + ", got " + shown(s);
            const std::string best = nearest_name(s, choices, 2);
            if (!best.empty()) msg += " (did you mean '" + best + "'?)";
            return msg;
        },
        "{" + list + "}");
}

CLI::Validator existing_file(const std::string& what) {
    return CLI::Validator(
        [what](std::string& s) -> std::string {
            std::error_code ec;
            const auto st = std::filesystem::status(s, ec);
            if (!std::filesystem::exists(st)) return what + " " + shown(s) + " does not exist";
            if (std::filesystem::is_directory(st))
                return what + " " + shown(s) + " is a directory, not a file";
            return {};
        },
        "FILE");
}

void write_with_provenance(const std::string& path, const std::string& content,
                           const std::string& comment, std::shared_ptr<ConfigDocument> doc) {
    if (!doc) doc = ConfigDocument::empty(path + ".toml");
    doc->add_resolved_section("provenance", provenance(command_line()));
    OutputTransaction tx;
    tx.stage(path, content);
    tx.stage(path + ".toml", "# " + comment + "\n" + doc->resolved_toml());
    tx.commit();
}

double checkpoint_seconds(const CommonOptions& o) {
    if (o.checkpoint_seconds) return *o.checkpoint_seconds;
    if (const char* s = std::getenv("SSSLAB_CHECKPOINT_SECONDS")) {
        char* end = nullptr;
        const double v = std::strtod(s, &end);
        if (end != s && *end == '\0' && std::isfinite(v) && v > 0) return v;
        throw InputError({"environment", 0, 0}, "SSSLAB_CHECKPOINT_SECONDS",
                         "must be a positive number of seconds, got '" + std::string(s) + "'");
    }
    return 30.0;
}

void add_resume_options(CLI::App& app, CommonOptions& o) {
    app.add_flag("--fresh", o.fresh,
                 "Start afresh even if a checkpoint of an earlier run is there (it is replaced). "
                 "Without it a run resumes from a checkpoint of the same input and refuses one of "
                 "other input, saying what differs");
    add_checkpoint_seconds_option(app, o);
}

void add_checkpoint_seconds_option(CLI::App& app, CommonOptions& o) {
    app.add_option("--checkpoint-seconds", o.checkpoint_seconds,
                   "Seconds between checkpoints (default 30, or SSSLAB_CHECKPOINT_SECONDS)")
        ->check(positive_number());
}

SampleBudget budget_from(const CommonOptions& o) {
    SampleBudget b;
    b.samples = o.photons;
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
