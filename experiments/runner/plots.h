// Plots of an experiment, drawn by scripts/plot.py (embedded in the binary) with matplotlib.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace ssslab::runner {

struct ExperimentRun;

struct PlotFile {
    std::string section;  ///< where the report shows it: "profiles", "convergence", "realtime", ...
    std::string title;
    std::string stem;  ///< plots/<name>, without extension (PNG and SVG exist)
    std::string caption;
};

struct PlotResult {
    std::vector<PlotFile> plots;
    std::string problem;  ///< why there are no plots, if there are none
};

class ArtifactCache;

/// A plot spec (JSON for scripts/plot.py), the tables it reads (relative to the results folder)
/// and its report entry.
struct PlotRequest {
    std::string json;
    std::vector<std::string> inputs;
    PlotFile file;
};

/// Draw the plots the experiment asks for into <dir>/plots/ (CSV inputs already in <dir>), with
/// draw_plots. The plugin studies' plots (study.h StudyResult::plots) are drawn by the runner
/// after each study's files are written.
PlotResult make_plots(const ExperimentRun& r, const std::filesystem::path& dir,
                      const ArtifactCache& cache, bool quiet);

/// Draw `requests` into <dir>/plots/ (their input tables, relative to <dir>, already there), in
/// one Python process. A plot is an artifact too, keyed by the plot script, its spec and the
/// content of its input tables: one drawn before is copied from the cache. Never throws for a
/// missing or failing plotting tool: the result then has no plots and says why (`problem`).
/// The captions carry the notes plot.py writes beside each figure.
PlotResult draw_plots(const std::vector<PlotRequest>& requests, const std::filesystem::path& dir,
                      const ArtifactCache& cache, bool quiet);

/// A Python interpreter that can import matplotlib: $SSSLAB_PYTHON, Debian's /usr/bin/python3,
/// or python3 on the PATH. Empty if none.
std::string find_python();

/// A JSON string literal (quotes, backslashes and newlines escaped), for plot specs.
std::string json_string(const std::string& s);

/// scripts/plot.py, embedded at build time.
std::string_view plot_script();

}  // namespace ssslab::runner
