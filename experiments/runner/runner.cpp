#include "experiments/runner/runner.h"

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/crash_point.h"
#include "core/distributed.h"
#include "core/error.h"
#include "core/format.h"
#include "core/hash.h"
#include "core/provenance.h"
#include "experiments/runner/engines.h"
#include "experiments/runner/kernel_study.h"
#include "experiments/runner/plots.h"
#include "experiments/runner/report.h"
#include "experiments/runner/study.h"
#include "mcml/transport.h"
#include "volpath/pencil.h"

#include <tbb/task_group.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <mutex>
#include <optional>
#include <sstream>

#include <fcntl.h>
#include <stdio.h>  // renameat2 (glibc >= 2.28, _GNU_SOURCE)
#include <unistd.h>

namespace ssslab::runner {

namespace fs = std::filesystem;

namespace {

constexpr const char* kKind = "mcml-channel";
constexpr const char* kVolpathKind = "volpath-channel";

const char* kind_of(const ChannelNode& n) {
    return n.engine == "volpath" ? kVolpathKind : kKind;
}

std::string budget_text(const SampleBudget& b) {
    std::ostringstream os;
    if (b.samples) os << "photons = " << *b.samples;
    if (b.seconds) os << (os.tellp() > 0 ? ", " : "") << "seconds = " << *b.seconds;
    if (b.rel_error) os << (os.tellp() > 0 ? ", " : "") << "rel_error = " << *b.rel_error;
    return os.str();
}

SampleBudget scaled_budget(const SampleBudget& b, double factor) {
    SampleBudget s = b;
    if (b.samples)
        s.samples = std::max<std::int64_t>(
            100, static_cast<std::int64_t>(std::llround(static_cast<double>(*b.samples) * factor)));
    if (b.seconds) s.seconds = *b.seconds * factor;
    if (b.rel_error) s.rel_error = *b.rel_error / std::sqrt(factor);
    return s;
}

// The layers below the first of a layered medium (nothing for a homogeneous one, so that its
// keys and seeds do not change).
void add_lower_layers(ContentKey& k, const Medium& m, int c) {
    for (size_t i = 0; i < m.lower_layers.size(); ++i) {
        const MediumLayer& l = m.lower_layers[i];
        const std::string p = "layer" + std::to_string(i + 1) + ".";
        k.add(p + "sigma_a_per_cm", l.sigma_a_per_cm[c])
            .add(p + "sigma_s_per_cm", l.sigma_s_per_cm[c])
            .add(p + "g", l.g[c])
            .add(p + "eta", l.eta)
            .add(p + "thickness_cm", l.thickness_cm);
    }
}

// The seed of a node: independent streams for every material, channel and role, the same for
// the same medium whatever the experiment it appears in.
std::uint64_t derive_seed(std::uint64_t seed, const Medium& m, int c, const std::string& role) {
    ContentKey k("seed");
    k.add("experiment_seed", seed)
        .add("sigma_a_per_cm", m.sigma_a_per_cm[c])
        .add("sigma_s_per_cm", m.sigma_s_per_cm[c])
        .add("g", m.g[c])
        .add("eta", m.eta)
        .add("channel", c)
        .add("role", role);
    add_lower_layers(k, m, c);
    return std::stoull(k.hex().substr(0, 16), nullptr, 16);
}

ContentKey node_key(const ChannelNode& n) {
    const Medium& m = n.medium;
    const int c = n.channel;
    const bool volpath = n.engine == "volpath";
    ContentKey k(kind_of(n));
    if (volpath)
        k.add("engine_version", volpath::engine_version()).add("mode", n.volpath_mode);
    else
        k.add("engine_version", mcml::engine_version())
            .add("tally", "profile")
            .add("snapshots", true);
    // What both engines' results depend on: the channel's medium, the grid and the budget.
    k.add("sigma_a_per_cm", m.sigma_a_per_cm[c])
        .add("sigma_s_per_cm", m.sigma_s_per_cm[c])
        .add("g", m.g[c])
        .add("eta", m.eta)
        .add("eta_above", m.eta_above)
        .add("eta_below", m.eta_below)
        .add("thickness_cm", m.thickness_cm)
        .add("dr_cm", n.grid.dr_cm)
        .add("nr", n.grid.nr)
        .add("budget_photons", n.budget.samples ? *n.budget.samples : std::int64_t{-1})
        .add("budget_seconds", n.budget.seconds ? *n.budget.seconds : -1.0)
        .add("budget_rel_error", n.budget.rel_error ? *n.budget.rel_error : -1.0);
    add_lower_layers(k, m, c);
    if (volpath)
        k.add("batch_paths", n.batch_photons).add("seed", n.seed).add("snapshots", true);
    else
        k.add("batch_photons", n.batch_photons).add("seed", n.seed).add("stream", std::int64_t{0});
    return k;
}

mcml::ProfileGrid grid_for(const Experiment& e, const Medium& m) {
    return e.mcml.grid.apply(mcml::freude14_grid(m));
}

std::string manifest_toml(const ChannelNode& n) {
    auto doc = ConfigDocument::empty("manifest.toml");
    ConfigTable root = doc->root();
    ConfigTable a = root.table_or_empty("artifact");
    a.record("kind", std::string(kind_of(n)));
    a.record("key", n.key);
    a.record("material", n.material);
    a.record("channel", std::string(kChannelNames[n.channel]));
    a.record("role", n.role);
    a.record("canonical_description", n.key_text);
    ConfigTable r = root.table_or_empty("run");
    r.record("engine", n.engine);
    const bool volpath = n.engine == "volpath";
    const BatchRunResult& v = n.vresult;
    const mcml::RunResult& m = n.result;
    const volpath::PencilLayout L{n.grid.nr};
    r.record("engine_version", volpath
                                   ? std::string(volpath::engine_version()) + " " + n.volpath_mode
                                   : std::string(mcml::engine_version()));
    r.record("seed", static_cast<std::int64_t>(n.seed));
    r.record("budget", budget_text(n.budget));
    r.record("photons", static_cast<std::int64_t>(volpath ? v.samples : m.photons));
    r.record("batches", static_cast<std::int64_t>(volpath ? v.batches : m.batches));
    r.record("batch_photons", volpath ? n.batch_photons : m.batch_photons);
    r.record("wall_seconds", volpath ? v.seconds : m.seconds);
    r.record("stop_reason",
             std::string(volpath ? to_string(v.reason) : to_string(m.reason, "photons")));
    r.record("resumed_from_checkpoint",
             std::string((volpath ? v.resumed : m.resumed) ? "yes" : "no"));
    r.record("Rd", volpath ? v.mean[L.rd()] : m.mean(m.layout.rd));
    r.record("Rd_se", volpath ? v.se[L.rd()] : m.se[m.layout.rd]);
    doc->add_resolved_section("provenance", provenance());
    return doc->resolved_toml();
}

Provenance read_manifest(const fs::path& file, const std::string& key) {
    auto doc = ConfigDocument::parse_file(file.string());
    ConfigTable root = doc->root();
    ConfigTable r = root.require_table("run");
    ConfigTable p = root.require_table("provenance");
    Provenance pv;
    pv.key = key;
    pv.engine = r.string("engine");
    pv.engine_version = r.string("engine_version");
    pv.seed = static_cast<std::uint64_t>(r.integer("seed"));
    pv.budget = r.string("budget");
    pv.photons = static_cast<std::uint64_t>(r.integer("photons"));
    pv.batches = static_cast<std::uint64_t>(r.integer("batches"));
    pv.batch_photons = r.integer("batch_photons");
    pv.seconds = r.number("wall_seconds");
    pv.stop_reason = r.string("stop_reason");
    pv.resumed = r.string("resumed_from_checkpoint") == "yes";
    pv.revision = p.string("git_revision");
    pv.date_utc = p.string("date_utc");
    return pv;
}

// ---- tables ---------------------------------------------------------------------------------

std::string summary_csv(const ExperimentRun& r) {
    std::ostringstream os;
    os << "material,channel,mfp_mm,albedo,Rsp,Rd,Rd_se,Rd_beyond_grid,Rd_beyond_grid_se,A,A_se,"
          "Tt,Tt_se,photons,dr_mm,nr\n";
    for (const auto& m : r.exp.materials)
        for (int c = 0; c < 3; ++c) {
            const ChannelNode* n = find_node(r, m.label, c, "main");
            const mcml::RunResult& x = n->result;
            const auto& L = x.layout;
            os << m.label << ',' << kChannelNames[c] << ',' << format_g(m.medium.mfp_cm(c) * 10, 10)
               << ',' << format_g(m.medium.albedo(c), 10) << ',' << format_g(x.rsp, 10) << ','
               << format_g(x.mean(L.rd), 10) << ',' << format_g(x.se[L.rd], 10) << ','
               << format_g(x.mean(L.rd_r + static_cast<size_t>(L.nr)), 10) << ','
               << format_g(x.se[L.rd_r + static_cast<size_t>(L.nr)], 10) << ','
               << format_g(x.mean(L.a), 10) << ',' << format_g(x.se[L.a], 10) << ','
               << format_g(x.mean(L.tt), 10) << ',' << format_g(x.se[L.tt], 10) << ',' << x.photons
               << ',' << format_g(n->grid.dr_cm * 10, 10) << ',' << n->grid.nr << '\n';
        }
    return os.str();
}

std::string artifacts_csv(const ExperimentRun& r) {
    std::ostringstream os;
    os << "material,channel,role,key,engine,engine_version,budget,photons,batches,seed,wall_s,"
          "stop_reason,revision,date_utc,status,checkpoint\n";
    for (const auto& n : r.nodes) {
        const Provenance& p = n.provenance;
        os << n.material << ',' << kChannelNames[n.channel] << ',' << n.role << ',' << n.key << ','
           << p.engine << ',' << p.engine_version << ",\"" << p.budget << "\"," << p.photons << ','
           << p.batches << ',' << p.seed << ',' << format_g(p.seconds, 10) << ',' << p.stop_reason
           << ',' << p.revision << ',' << p.date_utc << ','
           << (p.computed_now ? "computed" : "reused") << ',' << (p.resumed ? "resumed" : "fresh")
           << '\n';
    }
    return os.str();
}

// A study's metrics.csv (metric,unit,value,tolerance): deterministic metrics for `ssslab check`.
void append_study_metrics(const std::map<std::string, std::string>& files, const std::string& study,
                          std::vector<Metric>& out) {
    const auto it = files.find("metrics.csv");
    if (it == files.end()) return;
    std::istringstream in(it->second);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::stringstream ls(line);
        for (std::string x; std::getline(ls, x, ',');) f.push_back(x);
        if (f.size() != 4)
            throw std::runtime_error("kernel study " + study + ": malformed metrics.csv line \"" +
                                     line + "\"");
        out.push_back({f[0], f[1], std::stod(f[2]), 0, false, std::stod(f[3])});
    }
}

// Inverse of metrics_csv() (values printed with 10 significant digits, as in metrics.csv).
void read_metrics_csv(const std::string& text, std::vector<Metric>& out) {
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::stringstream ls(line);
        for (std::string x; std::getline(ls, x, ',');) f.push_back(x);
        if (f.size() != 6)
            throw std::runtime_error("cached metrics.csv: malformed line \"" + line + "\"");
        out.push_back(
            {f[0], f[1], std::stod(f[2]), std::stod(f[3]), f[4] == "stochastic", std::stod(f[5])});
    }
}

std::string metrics_csv(const std::vector<Metric>& ms) {
    std::ostringstream os;
    os << "metric,unit,value,se,kind,tolerance\n";
    for (const auto& m : ms)
        os << m.name << ',' << m.unit << ',' << format_g(m.value, 10) << ',' << format_g(m.se, 10)
           << ',' << (m.stochastic ? "stochastic" : "deterministic") << ','
           << format_g(m.tolerance, 10) << '\n';
    return os.str();
}

// r R(r) relative L2 distance between two radial tallies (per-photon bin weights): the bin
// weight is the integral of 2 pi r R(r) over the bin, so it already is r R(r) dr up to 2 pi.
double rel_l2(const std::vector<double>& a, const std::vector<double>& ref, size_t off, int nr) {
    double num = 0, den = 0;
    for (int i = 0; i < nr; ++i) {
        const double d = a[off + static_cast<size_t>(i)] - ref[off + static_cast<size_t>(i)];
        num += d * d;
        den += ref[off + static_cast<size_t>(i)] * ref[off + static_cast<size_t>(i)];
    }
    return den > 0 ? std::sqrt(num / den) : 0.0;
}

// Convergence tables of one material: the progressive estimates of the main runs against the
// independent reference runs.
void convergence_tables(const ExperimentRun& r, const std::string& material, std::string& history,
                        std::string& snapshots) {
    std::ostringstream h, s;
    h << "channel,batches,photons,seconds,Rd,Rd_se,Rd_reference,Rd_reference_se,abs_error,"
         "rel_error,rel_se,efficiency_per_s\n";
    s << "channel,batches,photons,seconds,rRd_rel_l2_error,rRd_rel_l2_reference_floor\n";
    for (int c = 0; c < 3; ++c) {
        const ChannelNode* main = find_node(r, material, c, "main");
        const ChannelNode* ref = find_node(r, material, c, "reference");
        const mcml::RunResult& m = main->result;
        const mcml::RunResult& f = ref->result;
        const double rd_ref = f.mean(f.layout.rd), rd_ref_se = f.se[f.layout.rd];
        std::uint64_t b = 0;
        for (const auto& p : m.history) {
            ++b;
            if (b < 2) continue;  // a standard error needs two batches
            const double rel_se = p.se / p.value;
            h << kChannelNames[c] << ',' << b << ',' << p.samples << ',' << format_g(p.seconds, 10)
              << ',' << format_g(p.value, 10) << ',' << format_g(p.se, 10) << ','
              << format_g(rd_ref, 10) << ',' << format_g(rd_ref_se, 10) << ','
              << format_g(std::fabs(p.value - rd_ref), 10) << ','
              << format_g(std::fabs(p.value - rd_ref) / rd_ref, 10) << ',' << format_g(rel_se, 10)
              << ',' << format_g(1.0 / (rel_se * rel_se * p.seconds), 10) << '\n';
        }
        // The reference's own noise: the distance between two independent estimates with the
        // reference's standard errors, sqrt(sum se^2 / sum ref^2).
        double num = 0, den = 0;
        for (int i = 0; i < f.layout.nr; ++i) {
            const size_t k = f.layout.rd_r + static_cast<size_t>(i);
            num += f.se[k] * f.se[k];
            den += f.values[k] * f.values[k];
        }
        const double floor = den > 0 ? std::sqrt(num / den) : 0.0;
        for (const auto& sn : m.snapshots)
            s << kChannelNames[c] << ',' << sn.batches << ',' << sn.samples << ','
              << format_g(sn.seconds, 10) << ','
              << format_g(rel_l2(sn.mean, f.values, f.layout.rd_r, f.layout.nr), 10) << ','
              << format_g(floor, 10) << '\n';
    }
    history = h.str();
    snapshots = s.str();
}

}  // namespace

ExperimentRun plan(const Experiment& e, const RunOptions& o) {
    ExperimentRun r;
    r.exp = e;
    r.quick = o.quick;
    r.out_dir = o.results_root / e.name;
    const SampleBudget main_budget =
        o.quick ? scaled_budget(e.mcml.budget, e.mcml.quick_factor) : e.mcml.budget;
    ArtifactCache cache(o.results_root / "cache");
    auto add = [&](const MaterialEntry& m, int c, const std::string& role,
                   const SampleBudget& budget) {
        ChannelNode n;
        n.material = m.label;
        n.channel = c;
        n.role = role;
        n.medium = m.medium;
        n.grid = grid_for(e, m.medium);
        n.budget = budget;
        n.batch_photons = e.mcml.batch_photons;
        if (role == "volpath") {
            n.engine = "volpath";
            n.volpath_mode = e.volpath.mode;
            n.batch_photons = e.volpath.batch_paths;
        }
        n.seed = derive_seed(e.seed, m.medium, c, role);
        const ContentKey k = node_key(n);
        n.key = k.hex();
        n.key_text = k.text();
        n.cached = cache.find(kind_of(n), n.key).has_value();
        r.nodes.push_back(std::move(n));
    };
    for (const auto& m : e.materials)
        for (int c = 0; c < 3; ++c) add(m, c, "main", main_budget);
    if (e.volpath.enabled) {
        SampleBudget vb = e.volpath.budget;
        if (o.quick) vb = scaled_budget(vb, e.volpath.quick_factor);
        for (const auto& m : e.materials)
            for (int c = 0; c < 3; ++c) add(m, c, "volpath", vb);
    }
    if (e.convergence.enabled)
        for (const auto& label : e.convergence.materials)
            for (const auto& m : e.materials)
                if (m.label == label)
                    for (int c = 0; c < 3; ++c)
                        add(m, c, "reference",
                            scaled_budget(main_budget, e.convergence.reference_factor));
    return r;
}

void print_plan(const ExperimentRun& r, std::ostream& os, bool verbose) {
    int reuse = 0;
    for (const auto& n : r.nodes) reuse += n.cached;
    os << "experiment " << r.exp.name << (r.quick ? " (--quick)" : "") << ": " << r.nodes.size()
       << " artifacts, " << reuse << " cached, " << r.nodes.size() - static_cast<size_t>(reuse)
       << " to compute -> " << r.out_dir.string() << "/\n";
    os << "  " << std::left << std::setw(9) << "status" << std::setw(12) << "material"
       << std::setw(4) << "ch" << std::setw(11) << "role" << std::setw(26) << "budget"
       << "key\n";
    for (const auto& n : r.nodes) {
        os << "  " << std::left << std::setw(9) << (n.cached ? "reuse" : "compute") << std::setw(12)
           << n.material << std::setw(4) << kChannelNames[n.channel] << std::setw(11) << n.role
           << std::setw(26) << budget_text(n.budget) << n.key.substr(0, 16) << "\n";
        if (verbose) {
            std::istringstream is(n.key_text);
            std::string line;
            while (std::getline(is, line)) os << "        | " << line << "\n";
        }
    }
    os << "  outputs:";
    if (r.exp.profiles.enabled) os << " profiles";
    if (r.exp.profile_plots.enabled) os << " profile_plots";
    if (r.exp.convergence.enabled) os << " convergence";
    for (const auto& s : r.exp.studies) os << " " << s.study->describe();
    os << " report\n";
}

// What the plugin studies take of a run.
RenderStudyContext study_context(const ExperimentRun& r, const RunOptions& o) {
    RenderStudyContext ctx;
    ctx.seed = r.exp.seed;
    ctx.quick = r.quick;
    ctx.threads = o.threads;
    ctx.quiet = o.quiet;
    ctx.checkpoint_seconds = o.checkpoint_seconds;
    ctx.cancel = o.cancel;
    return ctx;
}

bool compute_nodes(ExperimentRun& r, const RunOptions& o) {
    ArtifactCache cache(o.results_root / "cache");
    std::mutex io;
    std::atomic<bool> interrupted{false};
    // A node continuing from its checkpoint says so before it runs on.
    auto say_resuming = [&](const ChannelNode& n, double done, std::optional<std::int64_t> total,
                            const char* unit) {
        if (o.quiet) return;
        std::lock_guard<std::mutex> lock(io);
        std::printf("  resuming %-10s %s %-9s from %.0f%s %s (checkpoint of [%s])\n",
                    n.material.c_str(), kChannelNames[n.channel], n.role.c_str(), done,
                    total ? (" of " + std::to_string(*total)).c_str() : "", unit,
                    n.key.substr(0, 16).c_str());
        std::fflush(stdout);
    };
    auto compute_volpath = [&](ChannelNode& n) {
        volpath::PencilOptions po;
        po.seed = n.seed;
        po.threads = o.threads;
        po.budget = n.budget;
        po.batch_paths = n.batch_photons;
        po.absorption = n.volpath_mode == "weighted" ? volpath::Absorption::kWeighted
                                                     : volpath::Absorption::kAnalog;
        po.only_channel = n.channel;
        po.cancel = o.cancel;
        po.snapshots = true;
        po.checkpoint_prefix = cache.checkpoint_prefix(kVolpathKind, n.key).string();
        po.checkpoint_seconds = o.checkpoint_seconds;
        po.on_resume = [&](int, const BatchProgress& p, const std::string&) {
            say_resuming(n, static_cast<double>(p.samples), po.budget.samples, "paths");
        };
        volpath::PencilRun run = volpath::simulate_pencil(n.medium, {n.grid.dr_cm, n.grid.nr}, po);
        n.vresult = std::move(run.runs[static_cast<size_t>(n.channel)]);
        if (run.interrupted) {
            interrupted = true;
            return;
        }
        const std::string manifest = manifest_toml(n);
        const fs::path dir = cache.store(
            kVolpathKind, n.key,
            {{"result.bin", serialize_batch_result(n.vresult)}, {"manifest.toml", manifest}});
        n.provenance = read_manifest(dir / "manifest.toml", n.key);
        n.provenance.computed_now = true;
        if (!o.quiet) {
            std::lock_guard<std::mutex> lock(io);
            std::printf("  computed %-10s %s %-9s %10llu paths   in %7.2f s  [%s]%s\n",
                        n.material.c_str(), kChannelNames[n.channel], n.role.c_str(),
                        static_cast<unsigned long long>(n.vresult.samples), n.vresult.seconds,
                        n.key.substr(0, 16).c_str(),
                        n.vresult.resumed ? " (resumed from its checkpoint)" : "");
            std::fflush(stdout);
        }
    };
    auto compute = [&](ChannelNode& n) {
        if (n.engine == "volpath") return compute_volpath(n);
        mcml::Grid g;
        g.dr = n.grid.dr_cm;
        g.nr = n.grid.nr;
        g.dz = n.medium.total_thickness_cm();
        g.nz = 1;
        g.na = 1;
        const mcml::RunSpec spec = mcml::run_for_channel(n.medium, n.channel, 1, g);
        mcml::EngineOptions eo;
        eo.seed = n.seed;
        eo.stream = 0;
        eo.threads = o.threads;
        eo.batch_photons = n.batch_photons;
        eo.mode = mcml::TallyMode::kProfile;
        eo.budget = n.budget;
        eo.cancel = o.cancel;
        eo.snapshots = true;
        eo.checkpoint_path = cache.checkpoint_prefix(kKind, n.key).string();
        eo.checkpoint_seconds = o.checkpoint_seconds;
        eo.on_resume = [&](const BatchProgress& p) {
            say_resuming(n, static_cast<double>(p.samples), n.budget.samples, "photons");
        };
        n.result = mcml::run_default(spec, eo);
        if (n.result.reason == BatchStop::kInterrupted) {
            interrupted = true;
            return;
        }
        const std::string manifest = manifest_toml(n);
        const fs::path dir = cache.store(
            kKind, n.key,
            {{"result.bin", mcml::serialize_result(n.result)}, {"manifest.toml", manifest}});
        n.provenance = read_manifest(dir / "manifest.toml", n.key);
        n.provenance.computed_now = true;
        if (!o.quiet) {
            std::lock_guard<std::mutex> lock(io);
            std::printf("  computed %-10s %s %-9s %10llu photons in %7.2f s  [%s]%s\n",
                        n.material.c_str(), kChannelNames[n.channel], n.role.c_str(),
                        static_cast<unsigned long long>(n.result.photons), n.result.seconds,
                        n.key.substr(0, 16).c_str(),
                        n.result.resumed ? " (resumed from its checkpoint)" : "");
            std::fflush(stdout);
        }
    };
    // Runs whose wall time is studied (the convergence materials) run alone, one after the
    // other with every core; the others run side by side. Under MPI every run is spread over
    // the ranks, one after the other (core/distributed.h: the ranks meet in each run in turn).
    auto timed = [&](const ChannelNode& n) {
        if (dist::active()) return true;
        auto in = [&](const std::vector<std::string>& ms) {
            return std::find(ms.begin(), ms.end(), n.material) != ms.end();
        };
        return (r.exp.convergence.enabled && in(r.exp.convergence.materials)) ||
               (r.exp.efficiency.enabled && in(r.exp.efficiency.materials));
    };
    tbb::task_group tg;
    for (auto& node : r.nodes) {
        if (node.cached) {
            const fs::path dir = *cache.find(kind_of(node), node.key);
            if (node.engine == "volpath")
                node.vresult = deserialize_batch_result(read_file(dir / "result.bin"),
                                                        (dir / "result.bin").string());
            else
                node.result = mcml::deserialize_result(read_file(dir / "result.bin"),
                                                       (dir / "result.bin").string());
            node.provenance = read_manifest(dir / "manifest.toml", node.key);
            ++r.reused;
            continue;
        }
        ++r.computed;
        if (!timed(node)) tg.run([&, np = &node] { compute(*np); });
    }
    tg.wait();
    for (auto& node : r.nodes)
        if (!node.cached && timed(node) && !interrupted) compute(node);
    if (interrupted) {
        r.interrupted = true;
        return false;
    }
    return true;
}

namespace {

// The finished results directory replaces the previous one in one step: renameat2's
// RENAME_EXCHANGE swaps the two names atomically (Linux >= 3.15), so a kill leaves either the
// old results or the new ones under results/<name>, never neither; the old then sit under the
// staging name and are removed (by this run, or as a dead run's staging by the next). Where the
// file system cannot exchange, the old directory is moved aside first.
void swap_in(const fs::path& stage, const fs::path& out_dir) {
    std::error_code ec;
    if (!fs::exists(out_dir, ec)) {
        fs::rename(stage, out_dir);
        crash_point("results.swapped");
        return;
    }
    if (::renameat2(AT_FDCWD, stage.c_str(), AT_FDCWD, out_dir.c_str(), RENAME_EXCHANGE) == 0) {
        crash_point("results.swapped");
        fs::remove_all(stage, ec);
        return;
    }
    const fs::path old = out_dir.string() + ".old-" + std::to_string(::getpid());
    fs::remove_all(old, ec);
    fs::rename(out_dir, old);
    crash_point("results.moved-aside");
    fs::rename(stage, out_dir);
    crash_point("results.swapped");
    fs::remove_all(old, ec);
}

// The engines' tables (crossval, pencil models, efficiency; engines.h) of the run: file name ->
// content, from the cache or computed and stored; their metrics appended to r.metrics.
std::map<std::string, std::string> engine_tables_cached(ExperimentRun& r,
                                                        const ArtifactCache& cache) {
    std::map<std::string, std::string> engine_files;
    // The engines' tables (crossval, pencil models, efficiency) are an artifact keyed by their
    // outputs' settings and the nodes they read: evaluating the models costs seconds.
    if (r.exp.crossval.enabled || r.exp.pencil.enabled || r.exp.efficiency.enabled) {
        ContentKey key("engine-tables");
        key.add("version", "engine-tables-2")  // 2: rel_l2_rR with its standard error
            .add("crossval", r.exp.crossval.enabled)
            .add("max_rel_se", r.exp.crossval.max_rel_se)
            .add("volpath_mode", r.exp.volpath.mode);
        r.exp.pencil.models.add_to_key(key);
        for (const auto& m : r.exp.efficiency.materials) key.add("efficiency", m);
        for (const auto& n : r.nodes) key.add(n.material + "." + n.role, n.key);
        const std::string k = key.hex();
        if (const auto dir = cache.find("engine-tables", k)) {
            for (const auto& f : fs::recursive_directory_iterator(*dir)) {
                if (!f.is_regular_file()) continue;
                const std::string rel = fs::relative(f.path(), *dir).string();
                if (rel == "metrics.csv")
                    read_metrics_csv(read_file(f.path()), r.metrics);
                else if (rel != "manifest.toml")
                    engine_files[rel] = read_file(f.path());
            }
            ++r.reused;
        } else {
            std::vector<Metric> ms;
            engine_files = engine_tables(r, ms);
            auto stored = engine_files;
            stored["metrics.csv"] = metrics_csv(ms);
            stored["manifest.toml"] = "[artifact]\nkind = \"engine-tables\"\nkey = \"" + k + "\"\n";
            cache.store("engine-tables", k, stored);
            r.metrics.insert(r.metrics.end(), ms.begin(), ms.end());
            ++r.computed;
        }
    }
    return engine_files;
}

// Every [[outputs.kernels]] study: from the cache or computed and stored, its files written
// under <stage>/kernels/<name>/, its metrics appended, its section given to the report.
void run_kernel_studies(ExperimentRun& r, const RunOptions& o, const ArtifactCache& cache,
                        const fs::path& stage, ReportContent& report) {
    for (const auto& study : r.exp.kernel_studies) {
        // A study is an artifact keyed by its spec and the ground-truth runs it reads.
        ContentKey key("kernel-study");
        key.add("version", kernel_study_version()).add("spec", study.canonical());
        for (const auto& m : study.materials)
            for (int c = 0; c < 3; ++c)
                key.add(m + "." + kChannelNames[c], find_node(r, m, c, "main")->key);
        StudyOutput so;
        so.spec = &study;
        so.key = key.hex();
        if (const auto dir = cache.find("kernel-study", so.key)) {
            for (const auto& f : fs::recursive_directory_iterator(*dir)) {
                if (!f.is_regular_file()) continue;
                const std::string rel = fs::relative(f.path(), *dir).string();
                if (rel != "manifest.toml") so.files[rel] = read_file(f.path());
            }
            auto doc = ConfigDocument::parse_file((*dir / "manifest.toml").string());
            so.summary = doc->root().require_table("study").string("summary");
            ++r.reused;
        } else {
            std::map<std::string, RadialProfile> profiles;
            for (const auto& m : study.materials) profiles[m] = material_profile(r, m);
            so.files = run_kernel_study(study, profiles, so.summary);
            auto doc = ConfigDocument::empty("manifest.toml");
            ConfigTable st = doc->root().table_or_empty("study");
            st.record("name", study.name);
            st.record("key", so.key);
            st.record("summary", so.summary);
            st.record("canonical_description", key.text());
            doc->add_resolved_section("provenance", provenance());
            auto all = so.files;
            all["manifest.toml"] = doc->resolved_toml();
            cache.store("kernel-study", so.key, all);
            so.computed_now = true;
            ++r.computed;
        }
        if (!o.quiet)
            std::printf("  %s kernel study %s: %s\n", so.computed_now ? "computed" : "reused  ",
                        study.name.c_str(), so.summary.c_str());
        for (const auto& [name, content] : so.files)
            write_file_atomic(stage / "kernels" / study.name / name, content);
        append_study_metrics(so.files, study.name, r.metrics);
        report.studies.push_back(std::move(so));
    }
}

// The plugin studies (study.h), in turn: what each returns is written and rendered here; false
// when one was interrupted (nothing of it is kept).
bool run_plugin_studies(ExperimentRun& r, const RunOptions& o, const ArtifactCache& cache,
                        const fs::path& stage, ReportContent& report) {
    for (const auto& s : r.exp.studies) {
        StudyInputs in;
        in.ctx = study_context(r, o);
        in.cache = &cache;
        in.results_root = o.results_root;
        StudyResult sr = s.study->run(in);
        if (sr.interrupted) {
            return false;
        }
        r.computed += sr.computed;
        r.reused += sr.reused;
        for (const auto& [name, content] : sr.files)
            write_file_atomic(stage / s.name / name, content);
        r.metrics.insert(r.metrics.end(), sr.metrics.begin(), sr.metrics.end());
        if (!o.quiet && !sr.summary.empty())
            std::printf("  %s: %s\n", s.name.c_str(), sr.summary.c_str());
        // Its plots, once the tables they read are written (none asked for: none drawn).
        report.sections.push_back(
            {std::move(sr.section), draw_plots(sr.plots, stage, cache, o.quiet)});
    }
    return true;
}

}  // namespace

bool execute(ExperimentRun& r, const RunOptions& o) {
    const auto t0 = std::chrono::steady_clock::now();
    ArtifactCache cache(o.results_root / "cache");
    cache.remove_stale_temporaries();
    {
        // Staging directories of killed runs (results/<name>.tmp-<pid>, .old-<pid>).
        std::error_code ec;
        const std::string prefix = r.exp.name + ".";
        if (fs::exists(o.results_root, ec))
            for (const auto& d : fs::directory_iterator(o.results_root, ec)) {
                const std::string n = d.path().filename().string();
                if ((n.rfind(prefix + "tmp-", 0) == 0 || n.rfind(prefix + "old-", 0) == 0) &&
                    owner_is_gone(d.path()))
                    fs::remove_all(d.path(), ec);
            }
    }
    if (!compute_nodes(r, o)) return false;
    r.metrics = compute_metrics(r);

    // Everything for results/<name>/ is written into a staging directory and swapped in at the
    // end, so an interrupted or failed run leaves the previous results as they were.
    const fs::path stage = r.out_dir.string() + ".tmp-" + std::to_string(::getpid());
    std::error_code ec;
    fs::remove_all(stage, ec);
    fs::create_directories(stage, ec);
    if (ec) throw IoError("cannot create '" + stage.string() + "': " + ec.message());
    ReportContent report;
    if (r.exp.profiles.enabled || r.exp.profile_plots.enabled) {
        for (const auto& m : r.exp.materials) {
            const RadialProfile p = material_profile(r, m.label);
            write_file_atomic(stage / "profiles" / (m.label + ".csv"),
                              p.to_csv(r.exp.profiles.unit));
        }
        write_file_atomic(stage / "summary.csv", summary_csv(r));
    }
    if (r.exp.convergence.enabled)
        for (const auto& m : r.exp.convergence.materials) {
            std::string h, s;
            convergence_tables(r, m, h, s);
            write_file_atomic(stage / "convergence" / (m + "_history.csv"), h);
            write_file_atomic(stage / "convergence" / (m + "_snapshots.csv"), s);
        }
    write_file_atomic(stage / "artifacts.csv", artifacts_csv(r));
    std::map<std::string, std::string> engine_files = engine_tables_cached(r, cache);
    for (const auto& [name, content] : engine_files) write_file_atomic(stage / name, content);
    run_kernel_studies(r, o, cache, stage, report);
    if (!run_plugin_studies(r, o, cache, stage, report)) {
        fs::remove_all(stage, ec);
        r.interrupted = true;
        return false;
    }
    write_file_atomic(stage / "metrics.csv", metrics_csv(r.metrics));
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    report.plots = make_plots(r, stage, cache, o.quiet);
    auto prov = provenance(o.command_line);
    prov.push_back({"quick", r.quick ? "true" : "false"});
    r.exp.doc->add_resolved_section("provenance", prov);
    write_file_atomic(stage / "experiment.toml",
                      "# ssslab run: the resolved experiment configuration and provenance\n" +
                          r.exp.doc->resolved_toml());
    report.engine_files = &engine_files;
    write_file_atomic(stage / "report.html", render_report(r, report));

    swap_in(stage, r.out_dir);
    return true;
}

std::vector<Metric> compute_metrics(const ExperimentRun& r) {
    std::vector<Metric> ms;
    for (const auto& m : r.exp.materials) {
        const ChannelNode* n0 = find_node(r, m.label, 0, "main");
        ms.push_back({m.label + ".nr", "bins", static_cast<double>(n0->grid.nr), 0, false, 0});
        ms.push_back({m.label + ".dr", "mm", n0->grid.dr_cm * 10, 0, false, 1e-12});
        for (int c = 0; c < 3; ++c) {
            const ChannelNode* n = find_node(r, m.label, c, "main");
            const mcml::RunResult& x = n->result;
            const auto& L = x.layout;
            const std::string base = m.label + "." + kChannelNames[c] + ".";
            ms.push_back({base + "Rd", "1", x.mean(L.rd), x.se[L.rd], true, 0});
            // Reflectance inside k mean free paths. The standard error is the quadrature sum of
            // the bins' errors: an upper bound, since a photon leaves through one bin only and
            // the bins are negatively correlated.
            const double mfp = m.medium.mfp_cm(c);
            for (int k : {1, 4, 16}) {
                double v = 0, var = 0;
                for (int i = 0; i < L.nr && (i + 1) * n->grid.dr_cm <= k * mfp; ++i) {
                    v += x.mean(L.rd_r + static_cast<size_t>(i));
                    var += x.se[L.rd_r + static_cast<size_t>(i)] *
                           x.se[L.rd_r + static_cast<size_t>(i)];
                }
                ms.push_back({base + "Rd_within_" + std::to_string(k) + "mfp", "1", v,
                              std::sqrt(var), true, 0});
            }
            ms.push_back({base + "Rd_beyond_grid", "1", x.mean(L.rd_r + static_cast<size_t>(L.nr)),
                          x.se[L.rd_r + static_cast<size_t>(L.nr)], true, 0});
        }
    }
    return ms;
}

}  // namespace ssslab::runner
