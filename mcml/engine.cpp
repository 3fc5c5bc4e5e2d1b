#include "mcml/engine.h"

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

#include <chrono>
#include <cmath>
#include <stdexcept>

namespace ssslab::mcml {

namespace {

// Bump when a change alters the numbers the default engine produces for a given seed.
constexpr const char* kEngineVersion = "mcml-default-3";

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

constexpr char kResultMagic[8] = {'S', 'S', 'S', 'L', 'R', 'E', 'S', '1'};

// Simulate one batch of photons (batch `index` of the stream) into `tally` (zeroed by the
// driver), reduce it, and return the scattering events.
[[gnu::noinline]] std::uint64_t simulate_batch_at(const RunSpec& run, const TallyLayout& layout,
                                                  const EngineOptions& opt, std::uint64_t index,
                                                  std::int64_t photons, double rsp, double* tally) {
    RngStream rng(opt.seed, rng_domain::kMcml + opt.stream, index);
    std::uint64_t events = 0;
    if (layout.mode == TallyMode::kFull) {
        FullSink<false> sink(run, layout, tally);
        Transport<false, RngStream, FullSink<false>> tr(run, rng, sink);
        tr.trace_interleaved(photons, rsp);
        events = tr.events();
    } else {
        ProfileSink sink(run, layout, tally);
        Transport<false, RngStream, ProfileSink> tr(run, rng, sink);
        tr.trace_interleaved(photons, rsp);
        events = tr.events();
    }
    reduce(run, tally, layout);
    return events;
}

// simulate_batch_at with its stack frame at the same offset within a 4 KiB page in every run.
// The photons, the random-number buffer and the spilled registers live in that frame, and a
// load whose address matches an earlier store's in the low 12 bits waits for it (4K aliasing):
// with the main thread's stack randomised below a page, one process in ten or twenty ran the
// loop 20-25 % slower than the next, the same build on the same input (a scan of the stack's
// offset showed windows of slow offsets). Aligning the frame makes the speed a property of the
// build again.
std::uint64_t simulate_batch(const RunSpec& run, const TallyLayout& layout,
                             const EngineOptions& opt, std::uint64_t index, std::int64_t photons,
                             double rsp, double* tally) {
    const auto frame = reinterpret_cast<std::uintptr_t>(__builtin_frame_address(0));
    void* pad = __builtin_alloca((frame & 4095u) + 16u);
    const std::uint64_t events = simulate_batch_at(run, layout, opt, index, photons, rsp, tally);
    asm volatile("" : : "r"(pad) : "memory");  // the padding stays until the call returned
    return events;
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
        opt.batch_photons > 0 ? opt.batch_photons : default_batch_samples(opt.budget, run.photons);

    BatchRunOptions bo;
    opt.apply(bo);
    bo.tally_size = layout.size;
    bo.batch_samples = res.batch_photons;
    bo.budget = opt.budget;
    if (!bo.budget.any()) bo.budget.samples = run.photons;
    bo.fingerprint = checkpoint_fingerprint(run, opt, res.batch_photons);
    bo.checkpoint_path = opt.checkpoint_path;
    bo.on_resume = opt.on_resume;
    bo.min_batches_for_error = opt.min_batches_for_error;
    bo.quantity = [&layout](const BatchAccumulator& acc, double& value, double& se) {
        budget_quantity(acc, layout, value, se);
    };
    bo.quantity_name = "Rd and Tt (no photon left the medium)";
    bo.on_batch = opt.on_batch;
    BatchRunResult r = run_batches(bo, [&](std::uint64_t index, std::int64_t photons, double* t) {
        return simulate_batch(run, layout, opt, index, photons, res.rsp, t);
    });

    res.values = std::move(r.mean);
    res.divisor = 1.0;
    res.se = std::move(r.se);
    res.photons = r.samples;
    res.batches = r.batches;
    res.events = r.work;
    res.seconds = r.seconds;
    res.threads = r.threads;
    res.reason = r.reason;
    res.resumed = r.resumed;
    res.history = std::move(r.history);
    res.snapshots = std::move(r.snapshots);
    return res;
}

RunResult run_compat(const RunSpec& run, Ran3& rng, const SampleBudget& budget,
                     const std::atomic<bool>* cancel,
                     const std::function<void(const BatchProgress&)>& on_batch) {
    check_run(run, /*compat=*/true);
    RunResult res;
    res.layout = TallyLayout::make(run, TallyMode::kFull);
    const TallyLayout& layout = res.layout;
    res.rsp = specular_reflectance(run.layers);
    res.threads = 1;
    const std::int64_t total = budget.samples ? *budget.samples : run.photons;
    res.batch_photons = default_batch_samples(SampleBudget{total, {}, {}}, total);

    RawTally global(layout), batch(layout);
    FullSink<true> sink(run, layout, global.v.data(), batch.v.data());
    Transport<true, Ran3, FullSink<true>> tr(run, rng, sink);
    BatchAccumulator acc(layout.size);
    const auto t0 = Clock::now();
    std::int64_t in_batch = 0, done = 0;
    res.reason = BatchStop::kSamples;
    while (done < total) {
        tr.trace(res.rsp);
        ++done;
        if (++in_batch == res.batch_photons || done == total) {
            reduce(run, batch.v.data(), layout);
            acc.add_batch(batch.v.data(), static_cast<std::uint64_t>(in_batch));
            batch.clear();
            in_batch = 0;
            BatchProgress p{acc.samples(), seconds_since(t0), 0.0, 0.0};
            budget_quantity(acc, layout, p.value, p.se);
            res.history.push_back(p);
            if (on_batch) on_batch(p);
            if (done == total) break;
            if (budget.seconds && p.seconds >= *budget.seconds) {
                res.reason = BatchStop::kTime;
                break;
            }
            if (budget.rel_error && acc.batches() >= 16 && p.value > 0 &&
                p.se <= *budget.rel_error * p.value) {
                res.reason = BatchStop::kRelError;
                break;
            }
            if (cancel && cancel->load(std::memory_order_relaxed)) {
                res.reason = BatchStop::kInterrupted;
                break;
            }
        }
    }
    reduce(run, global.v.data(), layout);
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
    put_batch_progress(w, r.history, r.snapshots);
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
    const auto reason = c.get<std::int32_t>();
    if (reason < 0 || reason > 3) throw InputError({name, 0, 0}, "", "corrupt stop reason");
    r.reason = static_cast<BatchStop>(reason);
    r.resumed = c.get<std::int32_t>() != 0;
    get_batch_progress(c, r.history, r.snapshots);
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
