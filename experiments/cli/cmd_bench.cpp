// `ssslab bench`: throughput of the MCML engine, single thread and all threads.
//
// Prints photons/ms and ns per scattering event for the van de Hulst slab (the MCML paper's
// validation case) and for the red channel of Skin1 (semi-infinite, albedo 0.959, n = 1.3, the
// Freude14 Table 6.1 grid). The reference figures of the original MCML 1.2.2 on one core of this
// machine class (2270 and 104 photons/ms) are from the issue that specified the port; `--write-mci`
// writes the exact inputs so the original can be timed on the same cases, and `--original PATH`
// times a build of the original program on them in the same run (best of the repeats, its whole
// process: reading the .mci, the photons, writing the .mco; each of its runs follows one of the
// port's on the same CPU, so both see the same machine) and prints the ratio per thread.
//
// `ssslab bench --kernels`: build time of every kernel model per material and channel, for the
// eleven Freude14 materials on the thesis grid (Table 6.1). The ground-truth profiles come from
// short MCML runs whose time is printed but is not part of the figures.
#include "approx/kernel2d.h"
#include "approx/model_spec.h"
#include "core/atomic_file.h"
#include "core/build_info.h"
#include "core/config.h"
#include "core/error.h"
#include "core/format.h"
#include "core/material.h"
#include "core/provenance.h"
#include "experiments/cli/bench_volpath.h"
#include "experiments/cli/commands.h"
#include "experiments/cli/common.h"
#include "mcml/engine.h"
#include "mcml/mci.h"
#include "mcml/profile.h"

#include <sched.h>
#include <sys/wait.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace ssslab::cli {

namespace {

struct BenchCase {
    std::string name;
    mcml::RunSpec run;
    mcml::TallyMode mode;
    std::int64_t photons;
    double original_photons_per_ms;  // 0: none quoted
};

mcml::RunSpec slab_run() {
    mcml::RunSpec r;
    r.out_name = "slab.mco";
    r.photons = 1'000'000;
    r.grid = {0.001, 0.01, 20, 50, 30};
    r.layers.resize(3);
    r.layers[0].n = 1.0;
    r.layers[1] = {0.0, 0.02, 1.0, 10.0, 90.0, 0.75, 0, 0, 0};
    r.layers[2].n = 1.0;
    r.layers[2].z0 = r.layers[2].z1 = 0.02;
    mcml::compute_critical_angles(r);
    return r;
}

mcml::RunSpec skin1_red_run() {
    const Medium skin = *find_material("Skin1");
    const auto g = mcml::freude14_grid(skin);
    mcml::Grid grid{g.dr_cm, g.dr_cm, 50, g.nr, 30};
    mcml::RunSpec r = mcml::run_for_channel(skin, 0, 200'000, grid);
    r.out_name = "skin1_red.mco";
    return r;
}

struct BenchArgs {
    int threads = 0;
    bool quick = false;
    int repeat = 3;
    std::string only;
    std::string write_mci;
    std::string original;  ///< a build of the original MCML 1.2.2, timed beside the port
    // --kernels
    bool kernels = false;
    bool volpath = false;
    bool render = false;
    bool realtime = false;
    bool integrations = false;
    std::string scenes = "experiments/scenes";
    std::string size;  ///< "N" or "WxH"; empty: the mode's default
    int spp = 16;
    int reference_factor = 4;        ///< --render: references of this many times the samples
    std::int64_t photons = 100'000;  ///< per channel, for the ground-truth profiles
    std::string csv;
    std::string backend = "software", platform = "auto";
};

// Quoted for /bin/sh.
std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// Keeps the calling thread (and the processes it starts) on the CPU it is running on while it
// lives, then restores its CPU set. The one-thread rows and the original's runs go to one CPU:
// on a virtual machine one virtual CPU can be slower than another for minutes (a busy
// hyperthread sibling on the host), and a ratio of runs on two of them measures the CPUs.
class PinnedToThisCpu {
  public:
    PinnedToThisCpu() {
        // TBB sizes its worker pool from the process's CPU set when it first starts a thread:
        // start it before the set shrinks, or later multi-threaded runs get no workers.
        tbb::parallel_for(0, tbb::info::default_concurrency(), [](int) {});
        saved_ok_ = ::sched_getaffinity(0, sizeof saved_, &saved_) == 0;
        const int cpu = ::sched_getcpu();
        if (!saved_ok_ || cpu < 0) return;
        cpu_set_t one;
        CPU_ZERO(&one);
        CPU_SET(cpu, &one);
        pinned_ = ::sched_setaffinity(0, sizeof one, &one) == 0;
    }
    PinnedToThisCpu(const PinnedToThisCpu&) = delete;
    PinnedToThisCpu& operator=(const PinnedToThisCpu&) = delete;
    ~PinnedToThisCpu() {
        if (pinned_) (void)::sched_setaffinity(0, sizeof saved_, &saved_);
    }

  private:
    cpu_set_t saved_{};
    bool saved_ok_ = false, pinned_ = false;
};

// The original program on one bench case: its .mci (the case's run with `photons` photons) in
// a scratch directory that lives as long as this object; each run() times one whole process
// (output discarded) and returns its photons per ms.
class OriginalProgram {
  public:
    OriginalProgram(const std::string& program, mcml::RunSpec run, std::int64_t photons)
        : program_(program), photons_(photons) {
        namespace fs = std::filesystem;
        dir_ = fs::temp_directory_path() /
               ("ssslab-bench-original-" + std::to_string(::getpid()) + "-" + run.out_name);
        fs::create_directories(dir_);
        run.photons = photons;
        out_ = run.out_name;
        write_file_atomic(dir_ / "in.mci", mcml::format_mci({run}));
        cmd_ = "cd " + shell_quote(dir_.string()) + " && " +
               shell_quote(fs::absolute(program).string()) + " in.mci > /dev/null 2>&1";
    }
    OriginalProgram(const OriginalProgram&) = delete;
    OriginalProgram& operator=(const OriginalProgram&) = delete;
    ~OriginalProgram() {
        std::error_code ec;
        std::filesystem::remove_all(dir_, ec);
    }

    double run() const {
        namespace fs = std::filesystem;
        fs::remove(dir_ / out_);
        const auto t0 = std::chrono::steady_clock::now();
        const int status = std::system(cmd_.c_str());
        const double s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (status != 0 || !fs::exists(dir_ / out_)) {
            const std::string how =
                status == 0 ? "it wrote no " + out_
                : WIFEXITED(status)
                    ? "exit status " + std::to_string(WEXITSTATUS(status))
                    : "killed by signal " +
                          std::to_string(WIFSIGNALED(status) ? WTERMSIG(status) : 0);
            throw InfeasibleError("--original: " + program_ + " failed on the bench's " +
                                  out_.substr(0, out_.size() - 4) + ".mci (" + how + ")");
        }
        return static_cast<double>(photons_) / (s * 1e3);
    }

  private:
    std::string program_, out_, cmd_;
    std::int64_t photons_;
    std::filesystem::path dir_;
};

int run_bench(const BenchArgs& a) {
    const int all = a.threads > 0 ? a.threads : tbb::info::default_concurrency();
    if (!a.write_mci.empty()) {
        namespace fs = std::filesystem;
        write_file_atomic(fs::path(a.write_mci) / "slab.mci", mcml::format_mci({slab_run()}));
        write_file_atomic(fs::path(a.write_mci) / "skin1_red.mci",
                          mcml::format_mci({skin1_red_run()}));
        std::printf("wrote %s/slab.mci and %s/skin1_red.mci\n", a.write_mci.c_str(),
                    a.write_mci.c_str());
        return 0;
    }
    const double q = a.quick ? 0.1 : 1.0;
    std::vector<BenchCase> cases = {
        {"slab (van de Hulst), full tallies", slab_run(), mcml::TallyMode::kFull,
         static_cast<std::int64_t>(2'000'000 * q), 2270},
        {"Skin1 red, full tallies", skin1_red_run(), mcml::TallyMode::kFull,
         static_cast<std::int64_t>(300'000 * q), 104},
        {"Skin1 red, profile tallies", skin1_red_run(), mcml::TallyMode::kProfile,
         static_cast<std::int64_t>(300'000 * q), 0},
    };
    // The original on every case it has a figure for (one thread): its runs alternate with the
    // port's one-thread runs, so that both see the same state of the machine (a busy spell slows
    // the runs of both, not the repeats of one). Checked first on each case, before any timing.
    std::map<std::string, double> original;
    std::map<std::string, std::unique_ptr<OriginalProgram>> programs;
    if (!a.original.empty())
        for (const auto& c : cases)
            if (c.original_photons_per_ms > 0 &&
                (a.only.empty() || c.name.find(a.only) != std::string::npos)) {
                programs[c.name] = std::make_unique<OriginalProgram>(a.original, c.run, c.photons);
                (void)programs[c.name]->run();
            }
    std::printf("MCML default engine, %d hardware threads used for 'all'\n", all);
    std::printf("%-34s %7s %10s %12s %12s %9s %11s\n", "case", "threads", "photons", "photons/ms",
                "ns/event", "events/ph", "x original");
    for (const auto& c : cases) {
        if (!a.only.empty() && c.name.find(a.only) == std::string::npos) continue;
        double single = 0.0;
        std::vector<int> counts = {1};
        if (all > 1) counts.push_back(all);
        for (int t : counts) {
            mcml::EngineOptions o;
            o.seed = 1;
            o.threads = t;
            o.mode = c.mode;
            o.budget.samples = c.photons;
            // Best of `repeat` runs: interference from other processes only ever slows a run.
            std::optional<PinnedToThisCpu> pin;
            if (t == 1) pin.emplace();
            const auto program = t == 1 ? programs.find(c.name) : programs.end();
            mcml::RunResult r;
            for (int k = 0; k < a.repeat; ++k) {
                mcml::RunResult again = mcml::run_default(c.run, o);
                if (k == 0 || again.seconds < r.seconds) r = std::move(again);
                if (program != programs.end()) {
                    const double ppms = program->second->run();
                    double& best = original[c.name];
                    best = std::max(best, ppms);
                }
            }
            const double ppms = static_cast<double>(r.photons) / (r.seconds * 1e3);
            const double ns_event = r.seconds * 1e9 / static_cast<double>(r.events);
            char ratio[32] = "-";
            const auto measured = original.find(c.name);
            const double reference =
                measured != original.end() ? measured->second : c.original_photons_per_ms;
            if (reference > 0) std::snprintf(ratio, sizeof ratio, "%.2f", ppms / reference / t);
            std::printf("%-34s %7d %10llu %12.1f %12.2f %9.1f %11s", c.name.c_str(), t,
                        static_cast<unsigned long long>(r.photons), ppms, ns_event * t,
                        static_cast<double>(r.events) / static_cast<double>(r.photons), ratio);
            if (t == 1)
                single = ppms;
            else
                std::printf("   scaling %.2f of %d", ppms / single, t);
            std::printf("\n");
        }
    }
    std::printf(
        "Each row is the fastest of %d runs. ns/event is CPU time per scattering event (wall "
        "time x threads). 'x original' is per thread, ",
        a.repeat);
    if (original.empty()) {
        std::printf(
            "against the original MCML 1.2.2 figure for this machine class (slab 2270, Skin1 red "
            "104 photons/ms on one core; --original PATH times a build of it here).\n");
    } else {
        std::printf(
            "against %s timed in this run on the same inputs (one thread, best of %d, "
            "its runs alternating with the port's on the same CPU):",
            a.original.c_str(), a.repeat);
        for (const auto& [name, ppms] : original)
            std::printf(" %s %.1f photons/ms;", name.c_str(), ppms);
        std::printf("\n");
    }
    return 0;
}

// ---- Kernel build times (--kernels) ------------------------------------------------------------

/// The models timed, in column order, with their short column headers.
struct TimedModel {
    const char* spec;
    const char* header;
};
const std::vector<TimedModel>& timed_models() {
    static const std::vector<TimedModel> m = {
        {"svd:rank=1", "svd1"},
        {"svd:rank=4,l1", "svd4,l1"},
        {"preintegration", "preint"},
        {"guided:k=1", "guided1"},
        {"guided:k=1.55,b=50", "guided1.55"},
        {"manual:table_a1,unit=mm", "manualA1"},
        {"deon:n=1", "deon1"},
        {"deon:n=6", "deon6"},
        {"ssss_skin", "ssss"},
    };
    return m;
}

/// One model on one channel: the best time of the repeats and the builder's info.
struct Timing {
    bool built = false;
    double seconds = 0;
    std::map<std::string, double> info;

    std::optional<double> get(const std::string& key) const {
        const auto it = info.find(key);
        return it == info.end() ? std::nullopt : std::optional<double>(it->second);
    }
};

struct MaterialTimes {
    std::string name;
    int n = 0;
    double h_mm = 0;
    double mcml_seconds = 0;  ///< the three ground-truth runs (not part of the benchmark)
    std::array<std::uint64_t, 3> photons{};
    std::array<double, 3> kernel2d_seconds{};
    std::vector<std::array<Timing, 3>> models;  ///< per timed_models() entry, per channel
};

/// Ground truth, Kernel2D and every model for one material.
MaterialTimes time_material(const MaterialPreset& preset,
                            const std::vector<approx::ModelSpec>& specs, std::int64_t photons,
                            int threads, int repeat) {
    MaterialTimes t;
    t.name = preset.name;
    const Medium& m = preset.medium;
    // The runner's ground truth: the thesis grid, profile tallies, channel = stream.
    const mcml::ProfileGrid grid = mcml::freude14_grid(m);
    mcml::ProfileOptions po;
    po.seed = 1;
    po.threads = threads;
    po.budget.samples = photons;
    auto t0 = Clock::now();
    const mcml::ProfileRun run = mcml::simulate_profile(m, grid, po);
    t.mcml_seconds = seconds_since(t0);
    for (int c = 0; c < 3; ++c)
        t.photons[static_cast<size_t>(c)] = run.channels[static_cast<size_t>(c)].photons;

    const approx::KernelGrid kg = approx::KernelGrid::from_profile(run.profile, 1);
    t.n = kg.n;
    t.h_mm = kg.h_mm;
    std::array<std::unique_ptr<approx::Kernel2D>, 3> kernels;
    for (int c = 0; c < 3; ++c) {
        double best = 0;
        for (int r = 0; r < repeat; ++r) {
            t0 = Clock::now();
            auto k = std::make_unique<approx::Kernel2D>(run.profile, c, kg);
            const double s = seconds_since(t0);
            if (r == 0 || s < best) best = s;
            kernels[static_cast<size_t>(c)] = std::move(k);
        }
        t.kernel2d_seconds[static_cast<size_t>(c)] = best;
    }

    const bool in_table_a1 = approx::freude14_table_a1().count(t.name) > 0;
    for (const auto& spec : specs) {
        std::array<Timing, 3> row;
        if (spec.name == "manual" && spec.flag("table_a1") && !in_table_a1) {
            t.models.push_back(row);
            continue;
        }
        for (int c = 0; c < 3; ++c) {
            Timing& x = row[static_cast<size_t>(c)];
            approx::ModelContext ctx;
            ctx.material = t.name;
            ctx.channel = c;
            for (int r = 0; r < repeat; ++r) {
                t0 = Clock::now();
                approx::ModelResult res =
                    approx::build_model(spec, *kernels[static_cast<size_t>(c)], ctx);
                const double s = seconds_since(t0);
                if (!x.built || s < x.seconds) x.seconds = s;
                x.built = true;
                x.info = std::move(res.info);
            }
        }
        t.models.push_back(std::move(row));
    }
    return t;
}

int run_kernel_bench(const BenchArgs& a, int repeat) {
    const int threads = a.threads > 0 ? a.threads : tbb::info::default_concurrency();
    // The model builders (guided's passes) and MCML use oneTBB: cap every arena at `threads`.
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              static_cast<size_t>(threads));
    const std::int64_t photons = a.quick ? std::max<std::int64_t>(1, a.photons / 5) : a.photons;
    const auto& models = timed_models();
    std::vector<approx::ModelSpec> specs;
    for (const auto& m : models) specs.push_back(approx::parse_model(m.spec));

    const auto& presets = freude14_materials();
    std::vector<MaterialTimes> all;
    std::fprintf(stderr,
                 "kernel build times: %zu materials, MCML ground truth %lld photons per channel, "
                 "%d threads\n",
                 presets.size(), static_cast<long long>(photons), threads);
    for (size_t i = 0; i < presets.size(); ++i) {
        const auto t0 = Clock::now();
        all.push_back(time_material(presets[i], specs, photons, threads, repeat));
        const MaterialTimes& t = all.back();
        std::fprintf(stderr, "[%2zu/%zu] %-10s n = %5d  MCML %6.2f s  kernels %7.2f s\n", i + 1,
                     presets.size(), t.name.c_str(), t.n, t.mcml_seconds,
                     seconds_since(t0) - t.mcml_seconds);
        std::fflush(stderr);
    }

    // Table 1: seconds per kernel (one channel), materials x models.
    std::printf(
        "Kernel build time [s per kernel = one RGB channel], thesis grid (Freude14 Table 6.1)\n");
    std::printf("%-10s %2s %5s %9s %9s", "material", "ch", "n", "h_mm", "kernel2d");
    for (const auto& m : models) std::printf(" %10s", m.header);
    std::printf("\n");
    for (const auto& t : all)
        for (int c = 0; c < 3; ++c) {
            const size_t cc = static_cast<size_t>(c);
            if (c == 0)
                std::printf("%-10s %2s %5d %9s", t.name.c_str(), kChannelNames[c], t.n,
                            format_g(t.h_mm, 3).c_str());
            else
                std::printf("%-10s %2s %5s %9s", "", kChannelNames[c], "", "");
            std::printf(" %9s", format_g(t.kernel2d_seconds[cc], 3).c_str());
            for (const auto& row : t.models)
                std::printf(" %10s", row[cc].built ? format_g(row[cc].seconds, 3).c_str() : "-");
            std::printf("\n");
        }

    // Table 2: per material, the ground truth's cost and the guided solver's constraint error
    // (max over channels) and iterations (per channel).
    std::vector<size_t> guided_columns;
    for (size_t i = 0; i < specs.size(); ++i)
        if (specs[i].name == "guided") guided_columns.push_back(i);
    std::printf(
        "\nPer material: MCML ground truth time (3 channels; not part of the figures), "
        "kernel2d and models [s] summed over the 3 channels (models: over all columns), guided "
        "constraint error (max over channels) and iterations\n");
    std::printf("%-10s %9s %10s %9s %9s", "material", "MCML_s", "photons/ch", "kernel2d", "models");
    for (size_t i : guided_columns)
        std::printf(" %11s %16s", (std::string(models[i].header) + " err").c_str(),
                    (std::string(models[i].header) + " it R/G/B").c_str());
    std::printf("\n");
    double mcml_total = 0, kernel2d_total = 0, models_total = 0, worst_error = 0;
    struct Slowest {
        double seconds = -1;
        std::string material, model;
        int channel = 0;
    } slowest;
    for (const auto& t : all) {
        double k2d = 0, sum = 0;
        for (double s : t.kernel2d_seconds) k2d += s;
        for (size_t i = 0; i < t.models.size(); ++i)
            for (int c = 0; c < 3; ++c) {
                const Timing& x = t.models[i][static_cast<size_t>(c)];
                if (!x.built) continue;
                sum += x.seconds;
                if (x.seconds > slowest.seconds) slowest = {x.seconds, t.name, models[i].spec, c};
            }
        mcml_total += t.mcml_seconds;
        kernel2d_total += k2d;
        models_total += sum;
        std::printf("%-10s %9.2f %10llu %9s %9s", t.name.c_str(), t.mcml_seconds,
                    static_cast<unsigned long long>(t.photons[0]), format_g(k2d, 3).c_str(),
                    format_g(sum, 3).c_str());
        for (size_t i : guided_columns) {
            double err = 0;
            std::string its;
            for (int c = 0; c < 3; ++c) {
                const Timing& x = t.models[i][static_cast<size_t>(c)];
                err = std::max(err, x.get("constraint_error").value_or(0.0));
                const auto it = x.get("iterations");
                its += (c ? "/" : "") + (it ? std::to_string(static_cast<long long>(*it)) : "-");
            }
            worst_error = std::max(worst_error, err);
            std::printf(" %11s %16s", format_g(err, 3).c_str(), its.c_str());
        }
        std::printf("\n");
    }

    std::printf("\nTotal build time: models %s s, Kernel2D %s s (%zu materials x 3 channels)\n",
                format_g(models_total, 3).c_str(), format_g(kernel2d_total, 3).c_str(), all.size());
    if (slowest.seconds >= 0)
        std::printf("Slowest kernel: %s, %s %s, %s s\n", slowest.model.c_str(),
                    slowest.material.c_str(), kChannelNames[slowest.channel],
                    format_g(slowest.seconds, 3).c_str());
    std::printf("Largest guided constraint error |sum A - 1|: %s%s\n",
                format_g(worst_error, 3).c_str(), worst_error > 1e-6 ? "  (above 1e-6)" : "");
    std::printf("MCML ground truth (not counted): %s s in all, %lld photons per channel%s\n",
                format_g(mcml_total, 3).c_str(), static_cast<long long>(photons),
                a.quick ? " (--quick: a fifth)" : "");
    std::printf(
        "Each time is the fastest of %d run%s (--repeat; default 1 with --kernels), wall time "
        "around approx::build_model (kernel2d: the Kernel2D constructor), with oneTBB limited to "
        "%d thread%s (--threads). n = cells per quadrant side (2n per side), h = cell size. "
        "Guided optimization's weight matrix depends only on the grid and (k, b): it is built "
        "once per material, in the R channel's time.\n",
        repeat, repeat == 1 ? "" : "s", threads, threads == 1 ? "" : "s");
    std::printf("Columns:");
    for (const auto& m : models) std::printf(" %s = \"%s\";", m.header, m.spec);
    std::printf(" '-': Freude14 Table A.1 has no row for the material.\n");

    if (!a.csv.empty()) {
        std::ostringstream csv;
        csv << "material,channel,model,grid_n,h_mm,build_s,constraint_error,iterations\n";
        for (const auto& t : all)
            for (int c = 0; c < 3; ++c) {
                const size_t cc = static_cast<size_t>(c);
                csv << t.name << ',' << kChannelNames[c] << ",kernel2d," << t.n << ','
                    << format_g(t.h_mm, 8) << ',' << format_g(t.kernel2d_seconds[cc], 8) << ",,\n";
                for (size_t i = 0; i < t.models.size(); ++i) {
                    const Timing& x = t.models[i][cc];
                    if (!x.built) continue;
                    const auto err = x.get("constraint_error");
                    const auto it = x.get("iterations");
                    csv << t.name << ',' << kChannelNames[c] << ",\"" << models[i].spec << "\","
                        << t.n << ',' << format_g(t.h_mm, 8) << ',' << format_g(x.seconds, 8) << ','
                        << (err ? format_g(*err, 8) : "") << ',' << (it ? format_g(*it, 8) : "")
                        << '\n';
                }
            }
        write_with_provenance(a.csv, csv.str(),
                              "ssslab bench --kernels: provenance of " + a.csv +
                                  " (timings depend on the machine: see host_threads)");
        std::printf("wrote %s (+ .toml)\n", a.csv.c_str());
    }
    return 0;
}

/// "N" (N x N) or "WxH", sides in [1, 16384]; false for anything else.
bool parse_size(const std::string& s, int& w, int& h) {
    const auto side = [](const std::string& t, int& v) {
        if (t.empty() || t.size() > 5 || t.find_first_not_of("0123456789") != std::string::npos)
            return false;
        v = std::stoi(t);
        return v >= 1 && v <= 16384;
    };
    const size_t x = s.find('x');
    if (x == std::string::npos) return side(s, w) && side(s, h);
    return side(s.substr(0, x), w) && side(s.substr(x + 1), h);
}

}  // namespace

void register_bench(CLI::App& app, std::function<int()>& action) {
    auto a = std::make_shared<BenchArgs>();
    CLI::App* sub = app.add_subcommand(
        "bench",
        "Benchmark the MCML engine: photons/ms and ns per scattering event, one thread "
        "and all threads; with --kernels, the kernel models' build times instead");
    sub->add_option("--threads", a->threads, "Threads for the multi-threaded rows (default: all)")
        ->check(integer_in(0, 65536));
    sub->add_flag("--quick", a->quick, "A tenth of the photons (with --kernels: a fifth)");
    CLI::Option* repeat =
        sub->add_option("--repeat", a->repeat,
                        "Runs per row; the fastest is reported (default 3; 1 with --kernels)")
            ->check(integer_in(1, 1'000'000));
    CLI::Option* kernels = sub->add_flag(
        "--kernels", a->kernels,
        "Instead of MCML: time the kernel models' builds per channel for the eleven Freude14 "
        "materials on the thesis grid (the MCML ground truth is timed separately)");
    CLI::Option* volpath = sub->add_flag(
        "--volpath", a->volpath,
        "Instead: the volumetric path tracer against MCML on the same slabs (per-channel and "
        "hero modes), paths/ms and extrapolated time to 1 % relative error");
    volpath->excludes(kernels);
    CLI::Option* render = sub->add_flag(
        "--render", a->render,
        "Instead: the scene renderer on the built-in scenes (rays/s, extrapolated time to 1 % "
        "per pixel); with --scenes, --size, --spp, --case");
    render->excludes(kernels)->excludes(volpath);
    CLI::Option* realtime = sub->add_flag(
        "--realtime", a->realtime,
        "Instead: the real-time renderer's passes (rasterizer, SSS pass, both) on the built-in "
        "scenes, 1 thread and all, the SSS pass against a streaming memory floor; with "
        "--scenes, --size, --case, --repeat, --csv");
    realtime->excludes(kernels)->excludes(volpath)->excludes(render);
    sub->add_option("--backend", a->backend,
                    "With --realtime: software (default) or gl (also the GL twin's passes, timed "
                    "in the same run and checked against the CPU's)")
        ->check(CLI::IsMember({"software", "gl"}))
        ->needs(realtime);
    sub->add_option("--platform", a->platform,
                    "With --backend gl: the headless GL platform, auto (default), osmesa or egl")
        ->check(CLI::IsMember({"auto", "osmesa", "egl"}))
        ->needs(realtime);
    sub->add_flag("--integrations", a->integrations,
                  "With --realtime: also Munoz11's layered convolution and Jensen-Buhler's "
                  "hierarchical integration in place of the SSS pass (the paper's Munoz11 times "
                  "were measured at 800x600: --size 800x600)")
        ->needs(realtime);
    CLI::Option* scenes = sub->add_option(
        "--scenes", a->scenes,
        "With --render or --realtime: the scene folder (default experiments/scenes)");
    CLI::Option* size =
        sub->add_option("--size", a->size,
                        "With --render: image width and height N (default 256); with "
                        "--realtime: WxH (default 1920x1080; --quick: 480x270)")
            ->check(CLI::Validator(
                [](std::string& v) {
                    int w = 0, h = 0;
                    return parse_size(v, w, h)
                               ? std::string()
                               : "must be N or WxH with sides in 1..16384, got " + v;
                },
                "N|WxH"));
    sub->add_option("--spp", a->spp, "With --render: samples per pixel (default 16)")
        ->check(integer_in(1, 1'000'000))
        ->needs(render);
    sub->add_option("--reference-factor", a->reference_factor,
                    "With --render: measure each scene's error against a reference of this many "
                    "times the samples, rendered in the same run with another seed (default 4; 0: "
                    "none, the run's own standard errors only)")
        ->check(integer_in(0, 1000))
        ->needs(render);
    sub->add_option("--case", a->only, "Only the cases (or scenes) whose name contains this text")
        ->excludes(kernels)
        ->excludes(volpath);
    sub->add_option("--write-mci", a->write_mci,
                    "Write the benchmark inputs as .mci files into this directory (to time the "
                    "original program on the same cases) and exit")
        ->excludes(kernels);
    sub->add_option("--original", a->original,
                    "A build of the original MCML 1.2.2 (never part of ssslab): time it on the "
                    "same inputs in this run and print the ratio per thread")
        ->check(CLI::ExistingFile)
        ->excludes(kernels)
        ->excludes(volpath);
    sub->add_option("--photons", a->photons,
                    "With --kernels: MCML photons per channel for the ground-truth profiles "
                    "(default 100000)")
        ->check(integer_in(1, 1'000'000'000'000))
        ->needs(kernels);
    CLI::Option* csv = sub->add_option(
        "--csv", a->csv,
        "With --kernels: also write the times in long format (material, channel, model, grid_n, "
        "h_mm, build_s, constraint_error, iterations) to this file; with --realtime: scene, "
        "width, height, threads, pass, ms, floor_ms");
    sub->callback([a, repeat, scenes, size, csv, &action] {
        if (!a->render && !a->realtime && (scenes->count() > 0 || size->count() > 0))
            throw CLI::ValidationError(scenes->count() > 0 ? "--scenes" : "--size",
                                       "needs --render or --realtime");
        if (a->backend == "gl" && !SSSLAB_HAVE_GL)
            throw CLI::ValidationError("--backend",
                                       "this build has no GL twin (SSSLAB_WITH_GL; "
                                       "apt-get install libosmesa6-dev libegl-dev "
                                       "python3-glad)");
        if (!a->kernels && !a->realtime && csv->count() > 0)
            throw CLI::ValidationError("--csv", "needs --kernels or --realtime");
        int w = 0, h = 0;
        if (a->render && !a->size.empty() && (!parse_size(a->size, w, h) || w != h))
            throw CLI::ValidationError("--size", "with --render: one number N, got " + a->size);
        action = [a, explicit_repeat = repeat->count() > 0] {
            const int all = a->threads > 0 ? a->threads : tbb::info::default_concurrency();
            if (a->kernels) return run_kernel_bench(*a, explicit_repeat ? a->repeat : 1);
            if (a->realtime) {
                int width = a->quick ? 480 : 1920, height = a->quick ? 270 : 1080;
                if (!a->size.empty()) parse_size(a->size, width, height);
                return run_realtime_bench(all, a->quick, a->scenes, width, height,
                                          explicit_repeat ? a->repeat : (a->quick ? 1 : 3), a->only,
                                          a->csv, a->backend, a->platform, a->integrations);
            }
            if (a->render) {
                int side = 256, same = 256;
                if (!a->size.empty()) parse_size(a->size, side, same);
                return run_render_bench(all, a->quick, a->scenes, side, a->spp, a->only,
                                        a->reference_factor);
            }
            if (a->volpath)
                return run_volpath_bench(
                    a->threads > 0 ? a->threads : tbb::info::default_concurrency(), a->quick,
                    explicit_repeat ? a->repeat : 1);
            return run_bench(*a);
        };
    });
}

}  // namespace ssslab::cli
