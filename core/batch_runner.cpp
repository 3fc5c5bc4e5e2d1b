#include "core/batch_runner.h"

#include "core/atomic_file.h"
#include "core/binary_io.h"
#include "core/distributed.h"
#include "core/error.h"
#include "core/hash.h"

#include <tbb/concurrent_queue.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>

namespace ssslab {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

constexpr char kCheckpointMagic[8] = {'S', 'S', 'S', 'L', 'B', 'C', 'K', '1'};
constexpr char kResultMagic[8] = {'S', 'S', 'S', 'L', 'B', 'R', 'S', '1'};

// Messages between the ranks of a distributed run (core/distributed.h): a worker sends each
// batch it simulated (kBatch: index, samples, work, then the tally) and, when it stops, kDone;
// rank 0 tells the workers to stop (kStop) once the budget is met or the run is interrupted.
enum Tag : int { kBatch = 1, kDone = 2, kStop = 3 };
/// A kBatch message's header: index, samples, work.
constexpr std::size_t kBatchHeader = 3 * sizeof(std::uint64_t);

}  // namespace

void put_batch_progress(BinaryWriter& w, const std::vector<BatchProgress>& h,
                        const std::vector<BatchSnapshot>& s) {
    w.put<std::uint64_t>(h.size());
    for (const auto& p : h) {
        w.put(p.samples);
        w.put(p.seconds);
        w.put(p.value);
        w.put(p.se);
    }
    w.put<std::uint64_t>(s.size());
    for (const auto& sn : s) {
        w.put(sn.samples);
        w.put(sn.batches);
        w.put(sn.seconds);
        w.put_vec(sn.mean);
    }
}

void get_batch_progress(BinaryReader& r, std::vector<BatchProgress>& h,
                        std::vector<BatchSnapshot>& s) {
    const auto nh = r.get<std::uint64_t>();
    r.need(nh * 32);
    for (std::uint64_t i = 0; i < nh; ++i) {
        BatchProgress p;
        p.samples = r.get<std::uint64_t>();
        p.seconds = r.get<double>();
        p.value = r.get<double>();
        p.se = r.get<double>();
        h.push_back(p);
    }
    const auto ns = r.get<std::uint64_t>();
    for (std::uint64_t i = 0; i < ns; ++i) {
        BatchSnapshot sn;
        sn.samples = r.get<std::uint64_t>();
        sn.batches = r.get<std::uint64_t>();
        sn.seconds = r.get<double>();
        sn.mean = r.get_vec();
        s.push_back(std::move(sn));
    }
}

namespace {

struct Checkpoint {
    std::string fingerprint;
    std::uint64_t samples = 0, batches = 0, work = 0;
    double seconds = 0;
    std::vector<double> sum, q;
    std::vector<BatchProgress> history;
    std::vector<BatchSnapshot> snapshots;
};

void save_checkpoint(const std::string& path, const Checkpoint& c) {
    BinaryWriter w(kCheckpointMagic);
    w.put_str(c.fingerprint);
    w.put(c.samples);
    w.put(c.batches);
    w.put(c.work);
    w.put(c.seconds);
    w.put_vec(c.sum);
    w.put_vec(c.q);
    put_batch_progress(w, c.history, c.snapshots);
    write_file_atomic(path, w.bytes());
}

std::optional<Checkpoint> load_checkpoint(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return std::nullopt;
    const std::string data = read_file(path);
    BinaryReader r(data, path, kCheckpointMagic, "checkpoint");
    Checkpoint k;
    k.fingerprint = r.get_str();
    k.samples = r.get<std::uint64_t>();
    k.batches = r.get<std::uint64_t>();
    k.work = r.get<std::uint64_t>();
    k.seconds = r.get<double>();
    k.sum = r.get_vec();
    k.q = r.get_vec();
    get_batch_progress(r, k.history, k.snapshots);
    r.expect_end();
    return k;
}

}  // namespace

std::int64_t default_batch_samples(const SampleBudget& budget, std::int64_t run_samples) {
    const bool count_only = !budget.seconds && !budget.rel_error;
    const std::int64_t n = budget.samples ? *budget.samples : (count_only ? run_samples : 0);
    if (n <= 0) return 1000;
    if (n >= 32000) return std::max<std::int64_t>(1000, (n + 999) / 1000);
    return std::max<std::int64_t>(1, (n + 31) / 32);
}

const char* to_string(BatchStop s, const char* samples_word) {
    switch (s) {
        case BatchStop::kSamples:
            return samples_word;
        case BatchStop::kTime:
            return "time";
        case BatchStop::kRelError:
            return "rel_error";
        case BatchStop::kInterrupted:
            return "interrupted";
    }
    return "?";
}

std::string run_checkpoint_path(const std::string& prefix, const std::string& run) {
    return prefix + "." + run + ".ckpt";
}

void remove_checkpoints(const std::string& prefix) {
    if (outputs_discarded()) return;
    std::error_code ec;
    std::filesystem::remove(prefix + ".ckpt", ec);
    for (const char* run : {"R", "G", "B", "hero"})
        std::filesystem::remove(run_checkpoint_path(prefix, run), ec);
}

std::optional<std::string> batch_checkpoint_fingerprint(const std::string& path) {
    // Rank 0's checkpoint decides for every rank of a distributed run (core/distributed.h).
    return dist::from_root([&]() -> std::optional<std::string> {
        if (auto ck = load_checkpoint(path)) return std::move(ck->fingerprint);
        return std::nullopt;
    });
}

namespace {

// The rank that simulates batch `index` of a run over `ranks` ranks: batches are dealt in turn.
int batch_owner(std::uint64_t index, int ranks) {
    return static_cast<int>(index % static_cast<std::uint64_t>(ranks));
}

// One batch in flight: its index, samples, the work it reported and its tally.
struct BatchWork {
    std::uint64_t index = 0, work = 0;
    std::int64_t samples = 0;
    std::vector<double> tally;
};

// Rank 0 of a distributed run (core/distributed.h): batches arrive out of order (its own
// through the pipeline, the others' as kBatch messages) and wait in `pending_` until every
// batch before them is folded. Only the pipeline's last (serial) stage and the code after the
// pipeline call it, so it needs no lock.
class InOrderFolds {
  public:
    InOrderFolds(std::size_t tally_size, int ranks)
        : tally_size_(tally_size), ranks_(ranks), done_(static_cast<std::size_t>(ranks), 0) {}

    int owner(std::uint64_t index) const { return batch_owner(index, ranks_); }
    // Whether a worker stopped (interrupted) before sending a batch rank 0 needs.
    bool lost() const { return lost_; }
    // Rank 0's own batch w, simulated: it waits for its turn.
    void hold(BatchWork* w) { pending_[w->index] = w; }

    // Folds (fold(w)) every batch that is next in order, then gives it back (own: free_own(w));
    // waits for the others' batches while rank 0 needs one. Returns when the next batch is rank
    // 0's own, the run is over (stop or max_batches), or a worker has stopped without it.
    template <class Fold, class Free>
    void fold_in_order(const BatchAccumulator& acc, std::uint64_t max_batches,
                       const std::atomic<bool>& stop, Fold&& fold, Free&& free_own) {
        while (!stop.load(std::memory_order_relaxed) && !lost_) {
            const std::uint64_t k = acc.batches();
            if (auto it = pending_.find(k); it != pending_.end()) {
                BatchWork* w = it->second;
                pending_.erase(it);
                fold(w);
                release(w, free_own);
                continue;
            }
            if (k >= max_batches || owner(k) == 0) return;
            if (done_[static_cast<std::size_t>(owner(k))]) {
                lost_ = true;
                return;
            }
            receive_one(acc);
        }
    }

    // After the pipeline: tells the workers to stop, waits for every one's kDone and gives
    // back what is still pending (batches past the stop).
    template <class Free>
    void finish(const BatchAccumulator& acc, Free&& free_own) {
        for (int r = 1; r < ranks_; ++r) dist::notify(r, kStop);
        while (std::count(done_.begin() + 1, done_.end(), 1) < ranks_ - 1) receive_one(acc);
        dist::complete_notifications();
        for (auto& [index, w] : pending_) release(w, free_own);
        pending_.clear();
    }

  private:
    template <class Free>
    void release(BatchWork* w, Free& free_own) {
        if (owner(w->index) != 0)
            received_free_.push_back(w);
        else
            free_own(w);
    }

    // One message from a worker: a batch (into pending_) or its kDone.
    void receive_one(const BatchAccumulator& acc) {
        dist::Message m = dist::receive();
        if (m.tag == kDone) {
            done_[static_cast<std::size_t>(m.source)] = 1;
            return;
        }
        if (m.tag != kBatch || m.bytes.size() != kBatchHeader + tally_size_ * sizeof(double))
            throw std::runtime_error("MPI: an unexpected message from rank " +
                                     std::to_string(m.source));
        BatchWork* w = nullptr;
        if (received_free_.empty()) {
            received_pool_.push_back(std::make_unique<BatchWork>());
            w = received_pool_.back().get();
            w->tally.resize(tally_size_);
        } else {
            w = received_free_.back();
            received_free_.pop_back();
        }
        std::uint64_t h[3];
        static_assert(sizeof h == kBatchHeader);
        std::memcpy(h, m.bytes.data(), kBatchHeader);
        w->index = h[0];
        w->samples = static_cast<std::int64_t>(h[1]);
        w->work = h[2];
        std::memcpy(w->tally.data(), m.bytes.data() + kBatchHeader, tally_size_ * sizeof(double));
        if (owner(w->index) == 0 || w->index < acc.batches() || pending_.count(w->index))
            throw std::runtime_error("MPI: batch " + std::to_string(w->index) + " came from rank " +
                                     std::to_string(m.source));
        pending_[w->index] = w;
    }

    std::size_t tally_size_;
    int ranks_;
    std::map<std::uint64_t, BatchWork*> pending_;
    std::vector<std::unique_ptr<BatchWork>> received_pool_;  // Works of received batches
    std::vector<BatchWork*> received_free_;
    std::vector<char> done_;  // per rank: its kDone arrived
    bool lost_ = false;
};

// A worker rank of a distributed run: sends each batch to rank 0 in order and looks for rank
// 0's kStop after each.
struct BatchSender {
    bool stop_received = false;

    // Sends w; sets `stop` once rank 0 has said so.
    void send(const BatchWork& w, std::size_t tally_size, std::atomic<bool>& stop) {
        std::vector<char> msg(kBatchHeader + tally_size * sizeof(double));
        const std::uint64_t h[3] = {w.index, static_cast<std::uint64_t>(w.samples), w.work};
        std::memcpy(msg.data(), h, kBatchHeader);
        std::memcpy(msg.data() + kBatchHeader, w.tally.data(), tally_size * sizeof(double));
        dist::send(0, kBatch, msg.data(), msg.size());
        if (!stop_received && dist::poll(0, kStop)) {
            dist::receive(0);
            stop_received = true;
            stop = true;
        }
    }
    // After the pipeline: kDone, then (unless it came already) rank 0's kStop.
    void finish() {
        dist::send(0, kDone, nullptr, 0);
        if (!stop_received) dist::receive(0);
    }
};

}  // namespace

InputError checkpoint_refusal(const std::string& path, const std::string& before,
                              const std::string& now) {
    std::string what = key_difference(before, now);
    if (what.empty()) what = "its tally has another size";
    return InputError({path, 0, 0}, "",
                      "this checkpoint is of other input, so the run cannot resume from it (" +
                          what + "); remove the file or run again with --fresh to start afresh");
}

BatchRunResult run_batches(const BatchRunOptions& opt, const BatchFunction& simulate) {
    const SampleBudget& b = opt.budget;
    if (!b.any()) throw std::invalid_argument("run_batches: the budget has no limit");
    if (opt.batch_samples <= 0) throw std::invalid_argument("run_batches: batch_samples <= 0");
    if (b.rel_error && !opt.quantity)
        throw std::invalid_argument("run_batches: a rel_error budget needs a quantity");
    BatchRunResult res;
    res.threads = opt.threads > 0 ? opt.threads : tbb::this_task_arena::max_concurrency();

    const std::uint64_t bs = static_cast<std::uint64_t>(opt.batch_samples);
    const std::uint64_t total = b.samples ? static_cast<std::uint64_t>(*b.samples) : 0;
    const std::uint64_t max_batches = total > 0 ? (total + bs - 1) / bs : ~std::uint64_t(0);
    auto batch_size = [&](std::uint64_t index) -> std::int64_t {
        if (total == 0) return opt.batch_samples;
        return static_cast<std::int64_t>(std::min<std::uint64_t>(bs, total - index * bs));
    };

    // Under MPI (core/distributed.h) every rank simulates the batches dealt to it (index %
    // ranks == rank) and rank 0 folds all of them in batch order: the same statistics as one
    // process. Rank 0 alone reads and writes the checkpoint and decides when to stop.
    const bool distributed = dist::active();
    const int rank = dist::rank(), ranks = dist::size();
    const bool root = rank == 0;
    auto owner = [&](std::uint64_t index) { return batch_owner(index, ranks); };

    BatchAccumulator acc(opt.tally_size);
    double resumed_seconds = 0.0;
    if (root && !opt.checkpoint_path.empty() && !opt.fresh) {
        if (auto ck = load_checkpoint(opt.checkpoint_path)) {
            if (ck->fingerprint != opt.fingerprint || ck->sum.size() != opt.tally_size ||
                ck->q.size() != opt.tally_size)
                throw checkpoint_refusal(opt.checkpoint_path, ck->fingerprint, opt.fingerprint);
            acc.raw_sum() = std::move(ck->sum);
            acc.raw_q() = std::move(ck->q);
            acc.set_counts(ck->samples, ck->batches);
            res.work = ck->work;
            resumed_seconds = ck->seconds;
            res.history = std::move(ck->history);
            res.snapshots = std::move(ck->snapshots);
            res.resumed = true;
            if (opt.on_resume) {
                BatchProgress at{acc.samples(), resumed_seconds, 0.0, 0.0};
                if (!res.history.empty()) at = res.history.back();
                opt.on_resume(at);
            }
        }
    }

    using Work = BatchWork;
    const size_t tokens = static_cast<size_t>(2 * res.threads);
    std::vector<std::unique_ptr<Work>> pool;
    tbb::concurrent_queue<Work*> free_list;
    for (size_t i = 0; i < tokens; ++i) {
        pool.push_back(std::make_unique<Work>());
        pool.back()->tally.resize(opt.tally_size);
        free_list.push(pool.back().get());
    }

    const auto t0 = Clock::now();
    auto last_checkpoint = t0;
    std::atomic<bool> stop_flag{false};
    res.reason = BatchStop::kSamples;

    // Whether the budget is met after `nb` batches with progress `p`: sets the reason.
    auto budget_met = [&](std::uint64_t nb, const BatchProgress& p) {
        if (nb >= max_batches) {
            res.reason = BatchStop::kSamples;
            return true;
        }
        if (b.seconds && p.seconds >= *b.seconds) {
            res.reason = BatchStop::kTime;
            return true;
        }
        if (b.rel_error && nb >= static_cast<std::uint64_t>(opt.min_batches_for_error) &&
            p.value != 0 && p.se <= *b.rel_error * std::abs(p.value)) {
            res.reason = BatchStop::kRelError;
            return true;
        }
        return false;
    };
    // A checkpoint of a run that had finished (kept until its caller stored the result) or
    // that already holds the budget: nothing more to run, the result is the checkpoint's.
    if (res.resumed) {
        BatchProgress at{acc.samples(), resumed_seconds, 0.0, 0.0};
        if (opt.quantity && acc.batches() > 0) opt.quantity(acc, at.value, at.se);
        stop_flag = budget_met(acc.batches(), at);
    }
    // Where the run starts, and whether it is over already: rank 0's word.
    std::uint64_t first = acc.batches();
    if (distributed) {
        std::string start(sizeof(std::uint64_t) + 1, '\0');
        std::memcpy(start.data(), &first, sizeof first);
        start.back() = stop_flag ? 1 : 0;
        dist::broadcast(start);
        std::memcpy(&first, start.data(), sizeof first);
        stop_flag = start.back() != 0;
    }
    const std::uint64_t batches_at_start = first;
    // This rank's batches: first, first + ranks, ... shifted to the ones it owns.
    std::uint64_t next = first + static_cast<std::uint64_t>((rank - owner(first) + ranks) % ranks);

    auto write_checkpoint = [&]() {
        Checkpoint ck;
        ck.fingerprint = opt.fingerprint;
        ck.samples = acc.samples();
        ck.batches = acc.batches();
        ck.work = res.work;
        ck.seconds = resumed_seconds + seconds_since(t0);
        ck.sum = acc.raw_sum();
        ck.q = acc.raw_q();
        ck.history = res.history;
        ck.snapshots = res.snapshots;
        save_checkpoint(opt.checkpoint_path, ck);
    };

    auto fold = [&](Work* w) {
        if (stop_flag.load(std::memory_order_relaxed)) return;
        acc.add_batch(w->tally.data(), static_cast<std::uint64_t>(w->samples));
        res.work += w->work;
        BatchProgress p{acc.samples(), resumed_seconds + seconds_since(t0), 0.0, 0.0};
        if (opt.quantity) opt.quantity(acc, p.value, p.se);
        res.history.push_back(p);
        const std::uint64_t nb = acc.batches();
        if (opt.snapshots && nb >= 4 && (nb & (nb - 1)) == 0)
            res.snapshots.push_back({acc.samples(), nb, p.seconds, acc.means()});
        if (opt.on_batch) opt.on_batch(p);
        if (budget_met(nb, p)) {
            stop_flag = true;
        } else if (b.rel_error && !b.seconds && !b.samples && nb >= 10000 && p.value == 0) {
            throw InfeasibleError("a relative-error budget cannot be met: " + opt.quantity_name +
                                  " stayed 0 for 10000 batches");
        }
        if (!opt.checkpoint_path.empty() && !stop_flag &&
            seconds_since(last_checkpoint) >= opt.checkpoint_seconds) {
            write_checkpoint();
            last_checkpoint = Clock::now();
        }
    };
    auto cancelled = [&] { return opt.cancel && opt.cancel->load(std::memory_order_relaxed); };

    InOrderFolds in_order(opt.tally_size, ranks);  // rank 0 of a distributed run
    BatchSender sender;                            // a worker rank
    auto free_own = [&](Work* w) { free_list.push(w); };
    auto fold_in_order = [&] {
        in_order.fold_in_order(acc, max_batches, stop_flag, fold, free_own);
    };

    const std::uint64_t stride = static_cast<std::uint64_t>(ranks);
    auto body = [&] {
        tbb::parallel_pipeline(
            tokens,
            tbb::make_filter<void, Work*>(tbb::filter_mode::serial_in_order,
                                          [&](tbb::flow_control& fc) -> Work* {
                                              if (stop_flag.load(std::memory_order_relaxed) ||
                                                  next >= max_batches || cancelled()) {
                                                  fc.stop();
                                                  return nullptr;
                                              }
                                              Work* w = nullptr;
                                              if (!free_list.try_pop(w)) {
                                                  pool.push_back(std::make_unique<Work>());
                                                  w = pool.back().get();
                                                  w->tally.resize(opt.tally_size);
                                              }
                                              w->index = next;
                                              next += stride;
                                              w->samples = batch_size(w->index);
                                              return w;
                                          }) &
                tbb::make_filter<Work*, Work*>(tbb::filter_mode::parallel,
                                               [&](Work* w) -> Work* {
                                                   std::fill(w->tally.begin(), w->tally.end(), 0.0);
                                                   w->work = simulate(w->index, w->samples,
                                                                      w->tally.data());
                                                   return w;
                                               }) &
                tbb::make_filter<Work*, void>(tbb::filter_mode::serial_in_order, [&](Work* w) {
                    if (!distributed) {
                        fold(w);
                        free_list.push(w);
                    } else if (!root) {
                        if (!sender.stop_received) sender.send(*w, opt.tally_size, stop_flag);
                        free_list.push(w);
                    } else if (stop_flag.load(std::memory_order_relaxed) || in_order.lost()) {
                        free_list.push(w);
                    } else {
                        in_order.hold(w);
                        fold_in_order();
                    }
                }));
    };
    if (!stop_flag) {
        if (opt.threads > 0)
            tbb::task_arena(res.threads).execute(body);
        else
            body();
    }

    if (distributed && root) {
        // Rank 0's own batches are done; the others' may still be on their way.
        while (!stop_flag && !in_order.lost() && !cancelled() && acc.batches() < max_batches &&
               owner(acc.batches()) != rank)
            fold_in_order();
        in_order.finish(acc, free_own);
    } else if (distributed) {
        sender.finish();
    }

    if (!distributed || root) {
        res.seconds = resumed_seconds + seconds_since(t0);
        const bool finished = stop_flag.load();
        if (!finished) res.reason = BatchStop::kInterrupted;
        // Finished or not, the state is kept: a kill before the caller has stored the result
        // must not lose the run. The caller removes the checkpoint after storing
        // (remove_checkpoints).
        if (!opt.checkpoint_path.empty() &&
            !(res.resumed && finished && acc.batches() == batches_at_start))
            write_checkpoint();
        res.samples = acc.samples();
        res.batches = acc.batches();
        res.mean = acc.means();
        res.se = acc.standard_errors();
        if (opt.snapshots && finished && res.batches > 0 &&
            (res.snapshots.empty() || res.snapshots.back().batches != res.batches))
            res.snapshots.push_back(
                {res.samples, res.batches, res.history.back().seconds, res.mean});
    }
    if (distributed) {
        // Every rank returns rank 0's result.
        std::string bytes = root ? serialize_batch_result(res) : std::string();
        dist::broadcast(bytes);
        if (!root) res = deserialize_batch_result(bytes, "the result from rank 0");
    }
    return res;
}

std::string serialize_batch_result(const BatchRunResult& r) {
    BinaryWriter w(kResultMagic);
    w.put_vec(r.mean);
    w.put_vec(r.se);
    w.put(r.samples);
    w.put(r.batches);
    w.put(r.work);
    w.put(r.seconds);
    w.put<std::int32_t>(r.threads);
    w.put<std::int32_t>(static_cast<std::int32_t>(r.reason));
    w.put<std::int32_t>(r.resumed ? 1 : 0);
    put_batch_progress(w, r.history, r.snapshots);
    return std::move(w.bytes());
}

BatchRunResult deserialize_batch_result(const std::string& bytes, const std::string& name) {
    BinaryReader rd(bytes, name, kResultMagic, "batch result file");
    BatchRunResult r;
    r.mean = rd.get_vec();
    r.se = rd.get_vec();
    r.samples = rd.get<std::uint64_t>();
    r.batches = rd.get<std::uint64_t>();
    r.work = rd.get<std::uint64_t>();
    r.seconds = rd.get<double>();
    r.threads = rd.get<std::int32_t>();
    const auto reason = rd.get<std::int32_t>();
    if (reason < 0 || reason > 3) throw InputError({name, 0, 0}, "", "corrupt stop reason");
    r.reason = static_cast<BatchStop>(reason);
    r.resumed = rd.get<std::int32_t>() != 0;
    get_batch_progress(rd, r.history, r.snapshots);
    rd.expect_end();
    if (r.mean.size() != r.se.size())
        throw InputError({name, 0, 0}, "", "result file is inconsistent (sizes differ)");
    return r;
}

}  // namespace ssslab
