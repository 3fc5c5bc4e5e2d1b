#include "experiments/runner/plots.h"

#include "experiments/runner/engines.h"

#include "core/atomic_file.h"
#include "core/distributed.h"
#include "core/hash.h"
#include "experiments/runner/cache.h"
#include "experiments/runner/nodes.h"

#include <algorithm>

#include <cstdio>
#include <cstdlib>
#include <sstream>

#include <sys/wait.h>

namespace ssslab::runner {

namespace fs = std::filesystem;

namespace {

std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

int run_shell(const std::string& cmd) {
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

// The "notes" of a plot's <stem>.json (plot.py): what the figure shows where it departs from
// the expected, one sentence each, appended to the caption. Only the strings of that one array
// are read (plot.py writes them with json.dump: escapes \" \\ \n and \uXXXX).
std::vector<std::string> plot_notes(const std::string& json) {
    std::vector<std::string> notes;
    size_t at = json.find("\"notes\"");
    if (at == std::string::npos || (at = json.find('[', at)) == std::string::npos) return notes;
    std::string cur;
    bool in = false;
    for (size_t i = at + 1; i < json.size(); ++i) {
        const char c = json[i];
        if (!in) {
            if (c == ']') break;
            if (c == '"') in = true, cur.clear();
        } else if (c == '\\' && i + 1 < json.size()) {
            const char n = json[++i];
            if (n == 'n')
                cur += ' ';
            else if (n == 'u')
                cur += '?', i += 4;  // plot.py writes ASCII notes; keep the text readable
            else
                cur += n;
        } else if (c == '"') {
            in = false, notes.push_back(cur);
        } else {
            cur += c;
        }
    }
    return notes;
}

PlotResult with_notes(PlotResult p, const fs::path& dir) {
    for (PlotFile& f : p.plots) {
        const fs::path j = dir / (f.stem + ".json");
        if (!fs::exists(j)) continue;
        for (const std::string& n : plot_notes(read_file(j))) f.caption += " " + n;
    }
    return p;
}

}  // namespace

std::string json_string(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\')
            o += '\\', o += c;
        else if (c == '\n')
            o += "\\n";
        else
            o += c;
    }
    return o + "\"";
}

std::string find_python() {
    std::vector<std::string> candidates;
    if (const char* env = std::getenv("SSSLAB_PYTHON")) candidates.emplace_back(env);
    candidates.emplace_back("/usr/bin/python3");
    candidates.emplace_back("python3");
    for (const auto& py : candidates)
        if (run_shell(quote(py) + " -c 'import matplotlib' >/dev/null 2>&1") == 0) return py;
    return {};
}

PlotResult make_plots(const ExperimentRun& r, const fs::path& dir, const ArtifactCache& cache,
                      bool quiet) {
    const Experiment& e = r.exp;
    std::vector<PlotRequest> requests;
    if (e.profile_plots.enabled) {
        for (const auto& m : e.materials) {
            double mfp = 0;
            for (int c = 0; c < 3; ++c) mfp = std::max(mfp, m.medium.mfp_cm(c));
            const double len = e.profiles.unit == LengthUnit::kMm ? 10.0 : 1.0;
            const std::string stem = "plots/profile_" + m.label;
            const std::string csv = "profiles/" + m.label + ".csv";
            std::ostringstream js;
            js << "{\"kind\": \"profile\", \"csv\": " << json_string(csv)
               << ", \"title\": " << json_string(m.label + " (MCML, " + e.name + ")")
               << ", \"unit\": \"" << unit_name(e.profiles.unit) << "\""
               << ", \"linear_range\": " << e.profile_plots.linear_range_mfp * mfp * len
               << ", \"out\": " << json_string(stem) << "}";
            std::ostringstream caption;
            caption << m.label
                    << ": R_d(r) near zero on a linear scale, out to where every channel has "
                       "fallen to 2 % of its peak (at most the first "
                    << e.profile_plots.linear_range_mfp
                    << " mean free paths of the least attenuating channel), over the whole grid "
                       "on a log scale (as Freude 2014 Fig. 6.1), and 2 pi r R_d(r), whose area "
                       "is the total diffuse reflectance. Bands: +-2 standard errors.";
            requests.push_back({js.str(), {csv}, {"profiles", m.label, stem, caption.str()}});
        }
    }
    if (e.convergence.enabled) {
        for (const auto& m : e.convergence.materials) {
            const std::string stem = "plots/convergence_" + m;
            const std::string h = "convergence/" + m + "_history.csv";
            const std::string sn = "convergence/" + m + "_snapshots.csv";
            std::ostringstream js;
            js << "{\"kind\": \"convergence\", \"history\": " << json_string(h)
               << ", \"snapshots\": " << json_string(sn) << ", \"title\": " << json_string(m)
               << ", \"out\": " << json_string(stem) << "}";
            std::ostringstream caption;
            caption << m << ": error against wall time of the progressive estimates (after every "
                    << "batch) relative to an independent reference run with "
                    << e.convergence.reference_factor
                    << " times the photons; the standard error, the 1/sqrt(t) guide, the "
                       "reference's own noise floor, and the efficiency 1/(relative variance x "
                       "time), which is flat for a well-behaved estimator. These runs had every "
                       "core to themselves.";
            requests.push_back({js.str(), {h, sn}, {"convergence", m, stem, caption.str()}});
        }
    }
    for (const auto& st : e.kernel_studies) {
        const std::string sdir = "kernels/" + st.name + "/";
        if (st.singular_values > 0) {
            const std::string stem = "plots/" + st.name + "_singular_values";
            std::ostringstream js;
            js << "{\"kind\": \"singular_values\", \"csv\": "
               << json_string(sdir + "singular_values.csv")
               << ", \"title\": " << json_string(st.name) << ", \"out\": " << json_string(stem)
               << "}";
            requests.push_back({js.str(),
                                {sdir + "singular_values.csv"},
                                {"study:" + st.name, "singular values", stem,
                                 "The leading singular values of each channel's 2D kernel, "
                                 "divided by the first (as Freude14 Fig. 5.1)."}});
        }
        if (st.kernel_plots)
            for (const auto& m : st.materials) {
                const std::string stem = "plots/" + st.name + "_slices_" + m;
                std::ostringstream js;
                js << "{\"kind\": \"kernel_slices\", \"csv\": " << json_string(sdir + "slices.csv")
                   << ", \"material\": " << json_string(m)
                   << ", \"title\": " << json_string(m + " (" + st.name + ")")
                   << ", \"out\": " << json_string(stem) << "}";
                requests.push_back({js.str(),
                                    {sdir + "slices.csv"},
                                    {"study:" + st.name, m + " kernels", stem,
                                     m + ": the 2D kernels along the main axis (top) and the "
                                         "diagonal (bottom) per channel, ground truth dotted (as "
                                         "Freude14 Fig. 6.2)."}});
            }
    }
    for (PlotRequest& q : engine_plots(r)) requests.push_back(std::move(q));
    return draw_plots(requests, dir, cache, quiet);
}

PlotResult draw_plots(const std::vector<PlotRequest>& requests, const fs::path& dir,
                      const ArtifactCache& cache, bool quiet) {
    PlotResult out;
    struct Item {
        std::string json, key;  // spec entry; cache key
    };
    std::vector<Item> items;  // parallel to out.plots
    for (const PlotRequest& q : requests) {
        std::string content = std::string(plot_script()) + "\n" + q.json;
        for (const auto& in : q.inputs) content += "\n" + in + "\n" + read_file(dir / in);
        items.push_back({q.json, hash_hex(content)});
        out.plots.push_back(q.file);
    }
    // The ranks other than 0 of an MPI run draw nothing (core/distributed.h).
    if (out.plots.empty() || !dist::is_root()) return out;

    // Reuse what was drawn before; draw the rest in one Python process.
    std::error_code ec;
    fs::create_directories(dir / "plots", ec);
    std::vector<size_t> missing;
    for (size_t k = 0; k < items.size(); ++k) {
        const auto hit = cache.find_here("plot", items[k].key);
        if (!hit) {
            missing.push_back(k);
            continue;
        }
        for (const char* ext : {".png", ".svg", ".json"})
            if (fs::exists(*hit / (std::string("plot") + ext)))
                fs::copy_file(*hit / (std::string("plot") + ext), dir / (out.plots[k].stem + ext),
                              fs::copy_options::overwrite_existing);
    }
    if (missing.empty()) return with_notes(out, dir);

    const std::string python = find_python();
    if (python.empty()) {
        out.problem =
            "no Python with matplotlib was found (install python3-matplotlib, or set "
            "SSSLAB_PYTHON): tables and the report are written without plots";
        if (!quiet) std::fprintf(stderr, "ssslab run: %s\n", out.problem.c_str());
        out.plots.clear();
        return out;
    }
    std::ostringstream spec;
    spec << "{\"root\": " << json_string(dir.string()) << ",\n \"plots\": [";
    for (size_t i = 0; i < missing.size(); ++i)
        spec << (i ? ",\n  " : "\n  ") << items[missing[i]].json;
    spec << "]}\n";
    const fs::path script = dir / "plots" / ".plot.py";
    const fs::path spec_file = dir / "plots" / ".spec.json";
    const fs::path log = dir / "plots" / ".plot.log";
    write_file_atomic(script, std::string(plot_script()));
    write_file_atomic(spec_file, spec.str());
    const int rc =
        run_shell("MPLBACKEND=Agg " + quote(python) + " " + quote(script.string()) + " " +
                  quote(spec_file.string()) + " >" + quote(log.string()) + " 2>&1");
    if (rc != 0) {
        out.problem = "the plot script failed (exit " + std::to_string(rc) +
                      "): " + read_file(log).substr(0, 2000);
        if (!quiet) std::fprintf(stderr, "ssslab run: %s\n", out.problem.c_str());
        out.plots.clear();
    } else {
        for (size_t k : missing) {
            const std::string& stem = out.plots[k].stem;
            cache.store("plot", items[k].key,
                        {{"plot.png", read_file(dir / (stem + ".png"))},
                         {"plot.svg", read_file(dir / (stem + ".svg"))},
                         {"plot.json", read_file(dir / (stem + ".json"))},
                         {"manifest.toml", "[plot]\nspec = " + json_string(items[k].json) + "\n"}});
        }
    }
    fs::remove(script, ec);
    fs::remove(spec_file, ec);
    fs::remove(log, ec);
    return with_notes(out, dir);
}

}  // namespace ssslab::runner
