// A progress line on stderr with rate and ETA for long runs. Quiet when stderr is not a terminal
// (logs and CI stay clean); SSSLAB_PROGRESS=1 or 0 forces it on or off.
#pragma once

#include <chrono>
#include <string>

namespace ssslab {

class Progress {
  public:
    /// `total` <= 0 means unknown (no percentage, no ETA). `unit` names what is counted.
    Progress(std::string label, double total, std::string unit);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    /// Report `done` units finished; redraws at most a few times per second. `extra` is appended
    /// (e.g. the current relative error).
    void update(double done, const std::string& extra = {});
    /// The run continues from a checkpoint holding `done` units: the rate and the ETA count only
    /// what this run does from here on.
    void resume_from(double done) { base_ = done; }
    /// Clear the line.
    void finish();
    bool enabled() const { return enabled_; }

    /// Whether progress goes to stderr by default (a terminal, not overridden).
    static bool default_enabled();

  private:
    std::string label_, unit_;
    double total_;
    double base_ = 0;
    bool enabled_;
    bool drawn_ = false;
    std::chrono::steady_clock::time_point start_, last_;
};

/// "1.23k", "4.5M": a count with an SI suffix.
std::string si_count(double x);
/// "12s", "3m05s", "1h02m".
std::string format_duration(double seconds);

}  // namespace ssslab
