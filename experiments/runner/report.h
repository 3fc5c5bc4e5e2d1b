// report.html: one page with the experiment's description, tables and plots, and the
// provenance of every number (engine, budget, seed, time, revision of each artifact).
#pragma once

#include "experiments/runner/plots.h"
#include "experiments/runner/study.h"

#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab::runner {

struct ExperimentRun;

struct KernelStudySpec;

/// A kernel study's results as they go into the report.
struct StudyOutput {
    const KernelStudySpec* spec = nullptr;
    std::string key;
    bool computed_now = false;
    std::string summary;
    std::map<std::string, std::string> files;  ///< relative to kernels/<name>/
};

struct ReportContent {
    PlotResult plots;
    std::vector<StudyOutput> studies;
    const std::map<std::string, std::string>* engine_files = nullptr;  ///< engines.h tables
    /// The plugin studies' sections (study.h), in the experiment's order, each with the plots
    /// the runner drew for it.
    struct Study {
        StudySection section;
        PlotResult plots;
    };
    std::vector<Study> sections;
};

std::string render_report(const ExperimentRun& r, const ReportContent& c);

/// HTML-escaped text.
std::string esc(const std::string& s);
/// The figures of one report section.
void figures(std::ostringstream& os, const PlotResult& p, const std::string& section);
/// A CSV field: quoted where it holds a comma, a quote or a line break (model specs and
/// messages do: "manual:table_a1,unit=mm"); line breaks become spaces.
std::string csv_field(const std::string& v);
/// The rows of a CSV, its cells split at commas outside double quotes (model specs and notes
/// contain commas); quotes are dropped.
std::vector<std::vector<std::string>> parse_csv(const std::string& text);
/// A whole CSV as an HTML table with a title.
void csv_table(std::ostringstream& os, const std::string& csv, const char* title);

/// "0.4315 ± 0.0004": a value with its standard error, two significant digits of the error.
std::string with_error(double value, double se);

}  // namespace ssslab::runner
