#include "mcml/engine.h"

#include "core/atomic_file.h"
#include "core/batch_runner.h"
#include "core/binary_io.h"
#include "core/error.h"
#include "core/hash.h"
#include "core/rng.h"
#include "core/stats.h"
#include "mcml/mci.h"
#include "mcml/ran3.h"
#include "mcml/tally_sinks.h"
#include "mcml/transport.h"

#include <tbb/concurrent_queue.h>
#include <tbb/info.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace ssslab::mcml {

namespace {

// Bump when a change alters the numbers the default engine produces for a given seed.
constexpr const char* kEngineVersion = "mcml-default-3";

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// ---- checkpoints: a small binary file written atomically -------------------------------------

constexpr char kMagic[8] = {'S', 'S', 'S', 'L', 'C', 'K', 'P', '2'};

struct Checkpoint {
    std::string fingerprint;
    std::uint64_t photons = 0, batches = 0, events = 0;
    double seconds = 0;
    std::vector<double> sum, q;
    std::vector<ProgressPoint> history;
    std::vector<Snapshot> snapshots;
};

// The per-batch history and the snapshots, shared by checkpoints and result files.
void put_progress(BinaryWriter& w, const std::vector<ProgressPoint>& history,
                  const std::vector<Snapshot>& snapshots) {
    w.put<std::uint64_t>(history.size());
    for (const auto& p : history) w.put(p);
    w.put<std::uint64_t>(snapshots.size());
    for (const auto& sn : snapshots) {
        w.put(sn.photons);
        w.put(sn.batches);
        w.put(sn.seconds);
        w.put_vec(sn.mean);
    }
}

void get_progress(BinaryReader& c, std::vector<ProgressPoint>& history,
                  std::vector<Snapshot>& snapshots) {
    const auto nh = c.get<std::uint64_t>();
    for (std::uint64_t i = 0; i < nh; ++i) history.push_back(c.get<ProgressPoint>());
    const auto ns = c.get<std::uint64_t>();
    for (std::uint64_t i = 0; i < ns; ++i) {
        Snapshot sn;
        sn.photons = c.get<std::uint64_t>();
        sn.batches = c.get<std::uint64_t>();
        sn.seconds = c.get<double>();
        sn.mean = c.get_vec();
        snapshots.push_back(std::move(sn));
    }
}

void save_checkpoint(const std::string& path, const Checkpoint& c) {
    BinaryWriter w(kMagic);
    w.put_str(c.fingerprint);
    w.put(c.photons);
    w.put(c.batches);
    w.put(c.events);
    w.put(c.seconds);
    w.put_vec(c.sum);
    w.put_vec(c.q);
    put_progress(w, c.history, c.snapshots);
    write_file_atomic(path, w.bytes());
}

std::optional<Checkpoint> load_checkpoint(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return std::nullopt;
    const std::string data = read_file(path);
    BinaryReader c(data, path, kMagic, "MCML checkpoint");
    Checkpoint k;
    k.fingerprint = c.get_str();
    k.photons = c.get<std::uint64_t>();
    k.batches = c.get<std::uint64_t>();
    k.events = c.get<std::uint64_t>();
    k.seconds = c.get<double>();
    k.sum = c.get_vec();
    k.q = c.get_vec();
    get_progress(c, k.history, k.snapshots);
    return k;
}

constexpr char kResultMagic[8] = {'S', 'S', 'S', 'L', 'R', 'E', 'S', '1'};

// Simulate one batch of photons into `tally` (cleared first) and reduce it.
void simulate_batch(const RunSpec& run, const TallyLayout& layout, RngStream& rng,
                    std::int64_t photons, double rsp, RawTally& tally) {
    tally.clear();
    if (layout.mode == TallyMode::kFull) {
        FullSink<false> sink(run, layout, tally.v.data());
        Transport<false, RngStream, FullSink<false>> tr(run, rng, sink);
        tr.trace_interleaved(photons, rsp);
        tally.events = tr.events();
    } else {
        ProfileSink sink(run, layout, tally.v.data());
        Transport<false, RngStream, ProfileSink> tr(run, rng, sink);
        tr.trace_interleaved(photons, rsp);
        tally.events = tr.events();
    }
    reduce(run, tally.v, layout);
}

// The budget quantity: the larger of Rd and Tt (per photon) and its standard error.
void budget_quantity(const BatchAccumulator& acc, const TallyLayout& l, double& value, double& se) {
    const double rd = acc.mean(l.rd), tt = acc.mean(l.tt);
    const size_t i = rd >= tt ? l.rd : l.tt;
    value = acc.mean(i);
    se = acc.standard_error(i);
}

}  // namespace

const char* engine_version() {
    return kEngineVersion;
}

const char* to_string(StopReason r) {
    switch (r) {
        case StopReason::kPhotons:
            return "photons";
        case StopReason::kTime:
            return "time";
        case StopReason::kRelError:
            return "rel_error";
        case StopReason::kInterrupted:
            return "interrupted";
    }
    return "?";
}

std::int64_t default_batch_photons(const Budget& budget, std::int64_t run_photons) {
    const bool count_only = !budget.seconds && !budget.rel_error;
    const std::int64_t n = budget.photons ? *budget.photons : (count_only ? run_photons : 0);
    if (n <= 0) return 1000;
    if (n >= 32000) return std::max<std::int64_t>(1000, (n + 999) / 1000);
    return std::max<std::int64_t>(1, (n + 31) / 32);
}

std::string checkpoint_fingerprint(const RunSpec& run, const EngineOptions& o,
                                   std::int64_t batch_photons) {
    // Everything the tallies depend on, by name (the photon budget may change between a run
    // and its resumption; the output name does not matter).
    ContentKey k("mcml-checkpoint");
    k.add("engine", kEngineVersion)
        .add("seed", o.seed)
        .add("stream", o.stream)
        .add("batch_photons", batch_photons)
        .add("mode", o.mode == TallyMode::kFull ? "full" : "profile")
        .add("grid.dz", run.grid.dz)
        .add("grid.dr", run.grid.dr)
        .add("grid.nz", run.grid.nz)
        .add("grid.nr", run.grid.nr)
        .add("grid.na", run.grid.na);
    for (std::size_t i = 0; i < run.layers.size(); ++i) {
        const Layer& l = run.layers[i];
        const std::string p = i == 0                       ? std::string("above.")
                              : i + 1 == run.layers.size() ? std::string("below.")
                                                           : "layer" + std::to_string(i) + ".";
        k.add(p + "n", l.n);
        if (i == 0 || i + 1 == run.layers.size()) continue;
        k.add(p + "mua", l.mua).add(p + "mus", l.mus).add(p + "g", l.g).add(p + "d", l.z1 - l.z0);
    }
    return k.text();
}

RunResult run_default(const RunSpec& run, const EngineOptions& opt) {
    check_run(run, /*compat=*/false);
    if (opt.stream >= 0x7000) throw std::invalid_argument("run_default: stream >= 0x7000");
    RunResult res;
    res.layout = TallyLayout::make(run, opt.mode);
    const TallyLayout& layout = res.layout;
    res.rsp = specular_reflectance(run.layers);
    res.batch_photons =
        opt.batch_photons > 0 ? opt.batch_photons : default_batch_photons(opt.budget, run.photons);
    // threads = 0: the caller's arena (all cores, shared with whatever else runs in it, e.g. other
    // runs of an experiment); threads > 0: an arena of its own with that many.
    res.threads = opt.threads > 0 ? opt.threads : tbb::this_task_arena::max_concurrency();

    const Budget& b = opt.budget;
    std::int64_t total = b.photons ? *b.photons : ((b.seconds || b.rel_error) ? 0 : run.photons);
    const std::uint64_t bp = static_cast<std::uint64_t>(res.batch_photons);
    const std::uint64_t max_batches =
        total > 0 ? (static_cast<std::uint64_t>(total) + bp - 1) / bp : ~std::uint64_t(0);
    auto batch_size = [&](std::uint64_t index) -> std::int64_t {
        if (total <= 0) return res.batch_photons;
        const std::uint64_t start = index * bp;
        return static_cast<std::int64_t>(std::min<std::uint64_t>(bp, total - start));
    };

    BatchAccumulator acc(layout.size);
    const std::string fingerprint = checkpoint_fingerprint(run, opt, res.batch_photons);
    double resumed_seconds = 0.0;
    if (!opt.checkpoint_path.empty() && !opt.fresh) {
        if (auto ck = load_checkpoint(opt.checkpoint_path)) {
            if (ck->fingerprint != fingerprint || ck->sum.size() != layout.size)
                throw checkpoint_refusal(opt.checkpoint_path, ck->fingerprint, fingerprint);
            acc.raw_sum() = std::move(ck->sum);
            acc.raw_q() = std::move(ck->q);
            acc.set_counts(ck->photons, ck->batches);
            res.events = ck->events;
            resumed_seconds = ck->seconds;
            res.history = std::move(ck->history);
            res.snapshots = std::move(ck->snapshots);
            res.resumed = true;
            if (opt.on_resume) {
                ProgressPoint at{acc.samples(), resumed_seconds, 0.0, 0.0};
                if (!res.history.empty()) at = res.history.back();
                opt.on_resume(at);
            }
        }
    }

    struct Work {
        std::uint64_t index = 0;
        std::int64_t photons = 0;
        RawTally tally;
        explicit Work(const TallyLayout& l) : tally(l) {}
    };
    const size_t tokens = static_cast<size_t>(2 * res.threads);
    std::vector<std::unique_ptr<Work>> pool;
    tbb::concurrent_queue<Work*> free_list;
    for (size_t i = 0; i < tokens; ++i) {
        pool.push_back(std::make_unique<Work>(layout));
        free_list.push(pool.back().get());
    }

    const auto t0 = Clock::now();
    auto last_checkpoint = t0;
    std::uint64_t next = acc.batches();
    bool stop = next >= max_batches;
    if (stop) res.reason = StopReason::kPhotons;
    std::atomic<bool> stop_flag{stop};

    auto write_checkpoint = [&]() {
        Checkpoint ck;
        ck.fingerprint = fingerprint;
        ck.photons = acc.samples();
        ck.batches = acc.batches();
        ck.events = res.events;
        ck.seconds = resumed_seconds + seconds_since(t0);
        ck.sum = acc.raw_sum();
        ck.q = acc.raw_q();
        ck.history = res.history;
        ck.snapshots = res.snapshots;
        save_checkpoint(opt.checkpoint_path, ck);
    };

    auto body = [&] {
        tbb::parallel_pipeline(
            tokens,
            tbb::make_filter<
                void,
                Work*>(tbb::filter_mode::serial_in_order, [&](tbb::flow_control& fc) -> Work* {
                if (stop_flag.load(std::memory_order_relaxed) || next >= max_batches ||
                    (opt.cancel && opt.cancel->load(std::memory_order_relaxed))) {
                    fc.stop();
                    return nullptr;
                }
                Work* w = nullptr;
                if (!free_list.try_pop(w)) {
                    pool.push_back(std::make_unique<Work>(layout));
                    w = pool.back().get();
                }
                w->index = next++;
                w->photons = batch_size(w->index);
                return w;
            }) & tbb::make_filter<Work*, Work*>(tbb::filter_mode::parallel, [&](Work* w) -> Work* {
                RngStream rng(opt.seed, rng_domain::kMcml + opt.stream, w->index);
                simulate_batch(run, layout, rng, w->photons, res.rsp, w->tally);
                return w;
            }) & tbb::make_filter<Work*, void>(tbb::filter_mode::serial_in_order, [&](Work* w) {
                if (!stop_flag.load(std::memory_order_relaxed)) {
                    acc.add_batch(w->tally.v.data(), static_cast<std::uint64_t>(w->photons));
                    res.events += w->tally.events;
                    ProgressPoint p{acc.samples(), resumed_seconds + seconds_since(t0), 0.0, 0.0};
                    budget_quantity(acc, layout, p.value, p.se);
                    res.history.push_back(p);
                    const std::uint64_t nb = acc.batches();
                    if (opt.snapshots && nb >= 4 && (nb & (nb - 1)) == 0)
                        res.snapshots.push_back({acc.samples(), nb, p.seconds, acc.means()});
                    if (opt.on_batch) opt.on_batch(p);
                    if (acc.batches() >= max_batches) {
                        res.reason = StopReason::kPhotons;
                        stop_flag = true;
                    } else if (b.seconds && p.seconds >= *b.seconds) {
                        res.reason = StopReason::kTime;
                        stop_flag = true;
                    } else if (b.rel_error &&
                               acc.batches() >=
                                   static_cast<std::uint64_t>(opt.min_batches_for_error) &&
                               p.value > 0 && p.se <= *b.rel_error * p.value) {
                        res.reason = StopReason::kRelError;
                        stop_flag = true;
                    } else if (b.rel_error && !b.seconds && !b.photons && acc.batches() >= 10000 &&
                               p.value == 0) {
                        throw InfeasibleError(
                            "a relative-error budget cannot be met: no photon has left "
                            "the medium in 10000 batches (Rd = Tt = 0)");
                    }
                    if (!opt.checkpoint_path.empty() && !stop_flag &&
                        seconds_since(last_checkpoint) >= opt.checkpoint_seconds) {
                        write_checkpoint();
                        last_checkpoint = Clock::now();
                    }
                }
                free_list.push(w);
            }));
    };
    if (opt.threads > 0)
        tbb::task_arena(res.threads).execute(body);
    else
        body();

    res.seconds = resumed_seconds + seconds_since(t0);
    const bool finished = stop_flag.load();
    if (!finished) res.reason = StopReason::kInterrupted;
    if (!opt.checkpoint_path.empty()) {
        if (finished) {
            std::error_code ec;
            std::filesystem::remove(opt.checkpoint_path, ec);
        } else {
            write_checkpoint();
        }
    }
    res.photons = acc.samples();
    res.batches = acc.batches();
    res.values = acc.means();
    res.divisor = 1.0;
    res.se = acc.standard_errors();
    if (opt.snapshots && finished && res.batches > 0 &&
        (res.snapshots.empty() || res.snapshots.back().batches != res.batches))
        res.snapshots.push_back({res.photons, res.batches, res.history.back().seconds, res.values});
    return res;
}

RunResult run_compat(const RunSpec& run, Ran3& rng, const Budget& budget,
                     const std::atomic<bool>* cancel,
                     const std::function<void(const ProgressPoint&)>& on_batch) {
    check_run(run, /*compat=*/true);
    RunResult res;
    res.layout = TallyLayout::make(run, TallyMode::kFull);
    const TallyLayout& layout = res.layout;
    res.rsp = specular_reflectance(run.layers);
    res.threads = 1;
    const std::int64_t total = budget.photons ? *budget.photons : run.photons;
    res.batch_photons = default_batch_photons(Budget{total, {}, {}}, total);

    RawTally global(layout), batch(layout);
    FullSink<true> sink(run, layout, global.v.data(), batch.v.data());
    Transport<true, Ran3, FullSink<true>> tr(run, rng, sink);
    BatchAccumulator acc(layout.size);
    const auto t0 = Clock::now();
    std::int64_t in_batch = 0, done = 0;
    res.reason = StopReason::kPhotons;
    while (done < total) {
        tr.trace(res.rsp);
        ++done;
        if (++in_batch == res.batch_photons || done == total) {
            reduce(run, batch.v, layout);
            acc.add_batch(batch.v.data(), static_cast<std::uint64_t>(in_batch));
            batch.clear();
            in_batch = 0;
            ProgressPoint p{acc.samples(), seconds_since(t0), 0.0, 0.0};
            budget_quantity(acc, layout, p.value, p.se);
            res.history.push_back(p);
            if (on_batch) on_batch(p);
            if (done == total) break;
            if (budget.seconds && p.seconds >= *budget.seconds) {
                res.reason = StopReason::kTime;
                break;
            }
            if (budget.rel_error && acc.batches() >= 16 && p.value > 0 &&
                p.se <= *budget.rel_error * p.value) {
                res.reason = StopReason::kRelError;
                break;
            }
            if (cancel && cancel->load(std::memory_order_relaxed)) {
                res.reason = StopReason::kInterrupted;
                break;
            }
        }
    }
    reduce(run, global.v, layout);
    res.seconds = seconds_since(t0);
    res.photons = static_cast<std::uint64_t>(done);
    res.batches = acc.batches();
    res.events = tr.events();
    res.values = std::move(global.v);
    res.divisor = static_cast<double>(done);
    res.se = acc.standard_errors();
    return res;
}

std::string serialize_result(const RunResult& r) {
    BinaryWriter w(kResultMagic);
    const TallyLayout& l = r.layout;
    w.put<std::int32_t>(l.mode == TallyMode::kFull ? 0 : 1);
    for (int v : {l.nr, l.nz, l.na, l.nl}) w.put<std::int32_t>(v);
    for (size_t v : {l.rd_ra, l.tt_ra, l.a_rz, l.rd_r, l.tt_r, l.a_layer, l.rd_a, l.tt_a, l.a_z,
                     l.a_l, l.rd, l.a, l.tt, l.energy, l.primary_size, l.size})
        w.put<std::uint64_t>(v);
    w.put_vec(r.values);
    w.put(r.divisor);
    w.put_vec(r.se);
    w.put(r.rsp);
    for (std::uint64_t v : {r.photons, r.batches, r.events}) w.put(v);
    w.put(r.batch_photons);
    w.put(r.seconds);
    w.put<std::int32_t>(r.threads);
    w.put<std::int32_t>(static_cast<std::int32_t>(r.reason));
    w.put<std::int32_t>(r.resumed ? 1 : 0);
    put_progress(w, r.history, r.snapshots);
    return std::move(w.bytes());
}

RunResult deserialize_result(const std::string& data, const std::string& name) {
    BinaryReader c(data, name, kResultMagic, "MCML result file");
    RunResult r;
    TallyLayout& l = r.layout;
    l.mode = c.get<std::int32_t>() == 0 ? TallyMode::kFull : TallyMode::kProfile;
    for (int* v : {&l.nr, &l.nz, &l.na, &l.nl}) *v = c.get<std::int32_t>();
    for (size_t* v : {&l.rd_ra, &l.tt_ra, &l.a_rz, &l.rd_r, &l.tt_r, &l.a_layer, &l.rd_a, &l.tt_a,
                      &l.a_z, &l.a_l, &l.rd, &l.a, &l.tt, &l.energy, &l.primary_size, &l.size})
        *v = c.get<std::uint64_t>();
    r.values = c.get_vec();
    r.divisor = c.get<double>();
    r.se = c.get_vec();
    r.rsp = c.get<double>();
    for (std::uint64_t* v : {&r.photons, &r.batches, &r.events}) *v = c.get<std::uint64_t>();
    r.batch_photons = c.get<std::int64_t>();
    r.seconds = c.get<double>();
    r.threads = c.get<std::int32_t>();
    r.reason = static_cast<StopReason>(c.get<std::int32_t>());
    r.resumed = c.get<std::int32_t>() != 0;
    get_progress(c, r.history, r.snapshots);
    if (r.values.size() != l.size || r.se.size() != l.size)
        throw InputError({name, 0, 0}, "", "result file is inconsistent (tally sizes differ)");
    return r;
}

McoResult mco_values(const RunSpec& run, const RunResult& r, bool compat) {
    return scale_full(run, r.values, r.layout, r.divisor, compat ? kMcmlPi : kPi, r.rsp);
}

McoResult mco_standard_errors(const RunSpec& run, const RunResult& r, bool compat) {
    return scale_full(run, r.se, r.layout, 1.0, compat ? kMcmlPi : kPi, 0.0);
}

}  // namespace ssslab::mcml
