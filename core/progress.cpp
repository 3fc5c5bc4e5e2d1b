#include "core/progress.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <unistd.h>

namespace ssslab {

bool Progress::default_enabled() {
    if (const char* env = std::getenv("SSSLAB_PROGRESS")) return std::strcmp(env, "0") != 0;
    if (!::isatty(STDERR_FILENO)) return false;
    const char* term = std::getenv("TERM");
    return !(term && std::strcmp(term, "dumb") == 0);
}

Progress::Progress(std::string label, double total, std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      enabled_(default_enabled()),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

Progress::~Progress() {
    finish();
}

std::string si_count(double x) {
    char buf[32];
    const char* suffix[] = {"", "k", "M", "G", "T"};
    int i = 0;
    while (std::fabs(x) >= 1000.0 && i < 4) x /= 1000.0, ++i;
    std::snprintf(buf, sizeof buf, i == 0 ? "%.0f%s" : "%.3g%s", x, suffix[i]);
    return buf;
}

std::string format_duration(double s) {
    char buf[32];
    if (!std::isfinite(s) || s < 0) return "?";
    const long t = std::lround(s);
    if (t < 60)
        std::snprintf(buf, sizeof buf, "%lds", t);
    else if (t < 3600)
        std::snprintf(buf, sizeof buf, "%ldm%02lds", t / 60, t % 60);
    else
        std::snprintf(buf, sizeof buf, "%ldh%02ldm", t / 3600, (t % 3600) / 60);
    return buf;
}

void Progress::update(double done, const std::string& extra) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (drawn_ && now - last_ < std::chrono::milliseconds(200)) return;
    last_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double rate = elapsed > 0 ? (done - base_) / elapsed : 0.0;
    std::string line = "\r\033[K" + label_ + "  " + si_count(done);
    if (total_ > 0) {
        char pct[16];
        std::snprintf(pct, sizeof pct, " (%.1f%%)", 100.0 * done / total_);
        line += "/" + si_count(total_) + " " + unit_ + pct;
    } else {
        line += " " + unit_;
    }
    line += "  " + si_count(rate) + " " + unit_ + "/s  elapsed " + format_duration(elapsed);
    if (total_ > 0 && rate > 0) line += "  ETA " + format_duration((total_ - done) / rate);
    if (!extra.empty()) line += "  " + extra;
    std::fputs(line.c_str(), stderr);
    std::fflush(stderr);
    drawn_ = true;
}

void Progress::finish() {
    if (enabled_ && drawn_) {
        std::fputs("\r\033[K", stderr);
        std::fflush(stderr);
    }
    drawn_ = false;
}

}  // namespace ssslab
