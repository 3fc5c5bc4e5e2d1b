// Studies as plugins: a study is read from its [outputs.<name>] table of an experiment config,
// runs on what the run gives it (seed, --quick, threads, the artifact cache, cancellation), and
// returns its metrics, files and report section as data (StudyResult): the runner loops over the
// registry (runner.cpp), writes the files under results/<experiment>/<name>/ and one writer
// renders every section (report.cpp, study_section_html). Adding a study is a folder
// experiments/runner/studies/<name>/ whose .cpp files define the study and register it with
// SSSLAB_REGISTER_STUDY(<name>, factory); the build compiles the folder and calls the registration
// (experiments/CMakeLists.txt, by glob); no runner file changes (docs/architecture.md, "Studies as
// plugins").
//
// The older studies (profiles, convergence, the engines' tables, kernel studies) are still wired
// into runner.cpp by hand; they read the MCML nodes the runner plans, and move here once that
// planning is part of this interface (realtime, render, spot_light and stiff are plugins).
#pragma once

#include "core/config.h"
#include "experiments/runner/nodes.h"
#include "experiments/runner/plots.h"
#include "experiments/runner/scene_renders.h"

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ssslab::runner {

/// A flip viewer: images of the same size shown one at a time in one place (buttons, the arrow
/// keys), each with its difference image (a checkbox, the key d) and its cut-outs below, under
/// one exposure slider. Paths are relative to the results folder.
struct FlipViewer {
    std::string id;         ///< the element's id (unique in the page)
    int width_px = 256;     ///< the shown image's width in the page
    std::string what;       ///< the caption's first words ("Subsurface layer (...)")
    std::string diff_of;    ///< what the differences are to ("the screen-space reference (10x)")
    std::size_t first = 0;  ///< the image shown at first
    struct Image {
        std::string caption, path, diff, cut, cut_diff;
    };
    std::vector<Image> images;
};

/// A study's section of the report, as data: the writer escapes the text and renders, in this
/// order, the paragraphs, the figures of its plot requests (StudyResult::plots whose section is
/// `plot_section`), the tables (CSV text, the header its first row), the figures (images by path
/// relative to the results folder, with their captions), the flip viewers and the subsections
/// (headings one level down, with ids of their own).
struct StudySection {
    std::string id, title;
    std::vector<std::string> paragraphs;
    std::string plot_section;
    struct Table {
        std::string title, csv;
    };
    std::vector<Table> tables;
    struct Figure {
        std::string path, caption;
    };
    std::vector<Figure> figures;
    std::vector<FlipViewer> viewers;
    std::vector<StudySection> subsections;
};

struct StudyResult {
    bool interrupted = false;
    int computed = 0, reused = 0;
    /// Files relative to results/<experiment>/<name>/ and their content.
    std::map<std::string, std::string> files;
    std::vector<Metric> metrics;
    /// Figures the runner draws once the files are written (plots.h; their CSVs among the
    /// files), shown in the sections whose plot_section names them.
    std::vector<PlotRequest> plots;
    StudySection section;
    std::string summary;  ///< one line for the terminal
};

/// What a study gets of the run: the scene studies' context (seed, --quick, threads, quiet,
/// checkpoint interval, cancellation), the artifact cache and the results root that holds it
/// (where the runner's MCML profiles are computed or reused: realtime_inputs.h).
struct StudyInputs {
    RenderStudyContext ctx;
    const ArtifactCache* cache = nullptr;
    std::filesystem::path results_root;
};

class Study {
  public:
    virtual ~Study() = default;
    /// What --dry-run lists for it ("spot_light (2 scenes, computed when run)").
    virtual std::string describe() const = 0;
    virtual StudyResult run(const StudyInputs& in) const = 0;
    /// What --quick multiplies its budgets by (the report's header says it).
    virtual double quick_factor() const { return 1.0; }
};

/// A study from its config table (InputError naming the key for bad values); `config_dir` is the
/// experiment config's folder, against which paths in the table resolve.
using StudyFactory =
    std::function<std::shared_ptr<const Study>(ConfigTable& table, const std::string& config_dir)>;

/// Every registered study by name (the key of its [outputs.<name>] table), in name order.
const std::map<std::string, StudyFactory>& study_registry();

namespace detail {
void register_study(const std::string& name, StudyFactory factory);
}

}  // namespace ssslab::runner

/// In a study's .cpp under experiments/runner/studies/<name>/: registers `factory` as the study
/// read from [outputs.<name>] (the build calls ssslab_register_study_<name>() from
/// study_registry()).
#define SSSLAB_REGISTER_STUDY(name, factory)                      \
    void ssslab_register_study_##name() {                         \
        ::ssslab::runner::detail::register_study(#name, factory); \
    }
