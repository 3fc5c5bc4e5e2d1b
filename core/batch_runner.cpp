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

namespace {

// The options run_batches refuses.
void check_batch_options(const BatchRunOptions& opt) {
    const SampleBudget& b = opt.budget;
    if (!b.any()) throw std::invalid_argument("run_batches: the budget has no limit");
    if (opt.batch_samples <= 0) throw std::invalid_argument("run_batches: batch_samples <= 0");
    if (b.rel_error && !opt.quantity)
        throw std::invalid_argument("run_batches: a rel_error budget needs a quantity");
}

// One run_batches call: its options, the state the steps share, and the steps, in the order
// run() takes them.
class BatchRun {
  public:
    BatchRun(const BatchRunOptions& opt, const BatchFunction& simulate)
        : opt_(opt),
          simulate_(simulate),
          b_(opt.budget),
          bs_(static_cast<std::uint64_t>(opt.batch_samples)),
          total_(b_.samples ? static_cast<std::uint64_t>(*b_.samples) : 0),
          max_batches_(total_ > 0 ? (total_ + bs_ - 1) / bs_ : ~std::uint64_t(0)),
          distributed_(dist::active()),
          rank_(dist::rank()),
          ranks_(dist::size()),
          root_(rank_ == 0),
          acc_(opt.tally_size),
          in_order_(opt.tally_size, ranks_) {
        res_.threads = opt.threads > 0 ? opt.threads : tbb::this_task_arena::max_concurrency();
    }

    BatchRunResult run() {
        if (root_ && !opt_.checkpoint_path.empty() && !opt_.fresh) resume();
        make_pool();
        t0_ = Clock::now();
        last_checkpoint_ = t0_;
        res_.reason = BatchStop::kSamples;
        agree_on_start();
        if (!stop_flag_) {
            auto body = [this] { pipeline(); };
            if (opt_.threads > 0)
                tbb::task_arena(res_.threads).execute(body);
            else
                body();
        }
        if (distributed_ && root_)
            drain_workers();
        else if (distributed_)
            sender_.finish();
        if (!distributed_ || root_) finish();
        if (distributed_) share_result();
        return std::move(res_);
    }

  private:
    // The samples of batch `index` (the last one of a sample budget may be short).
    std::int64_t batch_size(std::uint64_t index) const {
        if (total_ == 0) return opt_.batch_samples;
        return static_cast<std::int64_t>(std::min<std::uint64_t>(bs_, total_ - index * bs_));
    }
    int owner(std::uint64_t index) const { return batch_owner(index, ranks_); }
    bool cancelled() const { return opt_.cancel && opt_.cancel->load(std::memory_order_relaxed); }

    // Rank 0: the checkpoint's state, if there is one (refused if it is of other input).
    void resume() {
        auto ck = load_checkpoint(opt_.checkpoint_path);
        if (!ck) return;
        if (ck->fingerprint != opt_.fingerprint || ck->sum.size() != opt_.tally_size ||
            ck->q.size() != opt_.tally_size)
            throw checkpoint_refusal(opt_.checkpoint_path, ck->fingerprint, opt_.fingerprint);
        acc_.raw_sum() = std::move(ck->sum);
        acc_.raw_q() = std::move(ck->q);
        acc_.set_counts(ck->samples, ck->batches);
        res_.work = ck->work;
        resumed_seconds_ = ck->seconds;
        res_.history = std::move(ck->history);
        res_.snapshots = std::move(ck->snapshots);
        res_.resumed = true;
        if (opt_.on_resume) {
            BatchProgress at{acc_.samples(), resumed_seconds_, 0.0, 0.0};
            if (!res_.history.empty()) at = res_.history.back();
            opt_.on_resume(at);
        }
    }

    // The pipeline's tokens, each with a batch's Work.
    void make_pool() {
        tokens_ = static_cast<size_t>(2 * res_.threads);
        for (size_t i = 0; i < tokens_; ++i) {
            pool_.push_back(std::make_unique<BatchWork>());
            pool_.back()->tally.resize(opt_.tally_size);
            free_list_.push(pool_.back().get());
        }
    }

    // Whether the budget is met after `nb` batches with progress `p`: sets the reason.
    bool budget_met(std::uint64_t nb, const BatchProgress& p) {
        if (nb >= max_batches_) {
            res_.reason = BatchStop::kSamples;
            return true;
        }
        if (b_.seconds && p.seconds >= *b_.seconds) {
            res_.reason = BatchStop::kTime;
            return true;
        }
        if (b_.rel_error && nb >= static_cast<std::uint64_t>(opt_.min_batches_for_error) &&
            p.value != 0 && p.se <= *b_.rel_error * std::abs(p.value)) {
            res_.reason = BatchStop::kRelError;
            return true;
        }
        return false;
    }

    // Where the run starts and whether it is over already (rank 0's word), and this rank's
    // first batch.
    void agree_on_start() {
        // A checkpoint of a run that had finished (kept until its caller stored the result) or
        // that already holds the budget: nothing more to run, the result is the checkpoint's.
        if (res_.resumed) {
            BatchProgress at{acc_.samples(), resumed_seconds_, 0.0, 0.0};
            if (opt_.quantity && acc_.batches() > 0) opt_.quantity(acc_, at.value, at.se);
            stop_flag_ = budget_met(acc_.batches(), at);
        }
        std::uint64_t first = acc_.batches();
        if (distributed_) {
            std::string start(sizeof(std::uint64_t) + 1, '\0');
            std::memcpy(start.data(), &first, sizeof first);
            start.back() = stop_flag_ ? 1 : 0;
            dist::broadcast(start);
            std::memcpy(&first, start.data(), sizeof first);
            stop_flag_ = start.back() != 0;
        }
        batches_at_start_ = first;
        // This rank's batches: first, first + ranks, ... shifted to the ones it owns.
        next_ = first + static_cast<std::uint64_t>((rank_ - owner(first) + ranks_) % ranks_);
    }

    void write_checkpoint() {
        Checkpoint ck;
        ck.fingerprint = opt_.fingerprint;
        ck.samples = acc_.samples();
        ck.batches = acc_.batches();
        ck.work = res_.work;
        ck.seconds = resumed_seconds_ + seconds_since(t0_);
        ck.sum = acc_.raw_sum();
        ck.q = acc_.raw_q();
        ck.history = res_.history;
        ck.snapshots = res_.snapshots;
        save_checkpoint(opt_.checkpoint_path, ck);
    }

    // Folds batch w (the next in order) into the tally: progress, snapshot, the budget and a
    // checkpoint when one is due.
    void fold(BatchWork* w) {
        if (stop_flag_.load(std::memory_order_relaxed)) return;
        acc_.add_batch(w->tally.data(), static_cast<std::uint64_t>(w->samples));
        res_.work += w->work;
        BatchProgress p{acc_.samples(), resumed_seconds_ + seconds_since(t0_), 0.0, 0.0};
        if (opt_.quantity) opt_.quantity(acc_, p.value, p.se);
        res_.history.push_back(p);
        const std::uint64_t nb = acc_.batches();
        if (opt_.snapshots && nb >= 4 && (nb & (nb - 1)) == 0)
            res_.snapshots.push_back({acc_.samples(), nb, p.seconds, acc_.means()});
        if (opt_.on_batch) opt_.on_batch(p);
        if (budget_met(nb, p)) {
            stop_flag_ = true;
        } else if (b_.rel_error && !b_.seconds && !b_.samples && nb >= 10000 && p.value == 0) {
            throw InfeasibleError("a relative-error budget cannot be met: " + opt_.quantity_name +
                                  " stayed 0 for 10000 batches");
        }
        if (!opt_.checkpoint_path.empty() && !stop_flag_ &&
            seconds_since(last_checkpoint_) >= opt_.checkpoint_seconds) {
            write_checkpoint();
            last_checkpoint_ = Clock::now();
        }
    }

    // Rank 0 of a distributed run: folds what is next in order (InOrderFolds::fold_in_order).
    void fold_in_order() {
        auto fold_one = [this](BatchWork* w) { fold(w); };
        auto free_own = [this](BatchWork* w) { free_list_.push(w); };
        in_order_.fold_in_order(acc_, max_batches_, stop_flag_, fold_one, free_own);
    }

    // The pipeline's first stage: the next batch this rank owns, or nullptr once it stops.
    BatchWork* take_batch(tbb::flow_control& fc) {
        if (stop_flag_.load(std::memory_order_relaxed) || next_ >= max_batches_ || cancelled()) {
            fc.stop();
            return nullptr;
        }
        BatchWork* w = nullptr;
        if (!free_list_.try_pop(w)) {
            pool_.push_back(std::make_unique<BatchWork>());
            w = pool_.back().get();
            w->tally.resize(opt_.tally_size);
        }
        w->index = next_;
        next_ += static_cast<std::uint64_t>(ranks_);
        w->samples = batch_size(w->index);
        return w;
    }

    // The pipeline's last stage: folds w (one process), sends it (a worker) or holds it for its
    // turn (rank 0).
    void deliver(BatchWork* w) {
        if (!distributed_) {
            fold(w);
            free_list_.push(w);
        } else if (!root_) {
            if (!sender_.stop_received) sender_.send(*w, opt_.tally_size, stop_flag_);
            free_list_.push(w);
        } else if (stop_flag_.load(std::memory_order_relaxed) || in_order_.lost()) {
            free_list_.push(w);
        } else {
            in_order_.hold(w);
            fold_in_order();
        }
    }

    // Simulates this rank's batches, `tokens_` in flight, delivered in batch order.
    void pipeline() {
        tbb::parallel_pipeline(
            tokens_, tbb::make_filter<void, BatchWork*>(
                         tbb::filter_mode::serial_in_order,
                         [this](tbb::flow_control& fc) -> BatchWork* { return take_batch(fc); }) &
                         tbb::make_filter<BatchWork*, BatchWork*>(
                             tbb::filter_mode::parallel,
                             [this](BatchWork* w) -> BatchWork* {
                                 std::fill(w->tally.begin(), w->tally.end(), 0.0);
                                 w->work = simulate_(w->index, w->samples, w->tally.data());
                                 return w;
                             }) &
                         tbb::make_filter<BatchWork*, void>(tbb::filter_mode::serial_in_order,
                                                            [this](BatchWork* w) { deliver(w); }));
    }

    // Rank 0 of a distributed run, after the pipeline: its own batches are done; the others'
    // may still be on their way.
    void drain_workers() {
        while (!stop_flag_ && !in_order_.lost() && !cancelled() && acc_.batches() < max_batches_ &&
               owner(acc_.batches()) != rank_)
            fold_in_order();
        auto free_own = [this](BatchWork* w) { free_list_.push(w); };
        in_order_.finish(acc_, free_own);
    }

    // Rank 0 (or the one process): the stop reason, the last checkpoint and the result.
    void finish() {
        res_.seconds = resumed_seconds_ + seconds_since(t0_);
        const bool finished = stop_flag_.load();
        if (!finished) res_.reason = BatchStop::kInterrupted;
        // Finished or not, the state is kept: a kill before the caller has stored the result
        // must not lose the run. The caller removes the checkpoint after storing
        // (remove_checkpoints).
        if (!opt_.checkpoint_path.empty() &&
            !(res_.resumed && finished && acc_.batches() == batches_at_start_))
            write_checkpoint();
        res_.samples = acc_.samples();
        res_.batches = acc_.batches();
        res_.mean = acc_.means();
        res_.se = acc_.standard_errors();
        if (opt_.snapshots && finished && res_.batches > 0 &&
            (res_.snapshots.empty() || res_.snapshots.back().batches != res_.batches))
            res_.snapshots.push_back(
                {res_.samples, res_.batches, res_.history.back().seconds, res_.mean});
    }

    // A distributed run: every rank returns rank 0's result.
    void share_result() {
        std::string bytes = root_ ? serialize_batch_result(res_) : std::string();
        dist::broadcast(bytes);
        if (!root_) res_ = deserialize_batch_result(bytes, "the result from rank 0");
    }

    const BatchRunOptions& opt_;
    const BatchFunction& simulate_;
    const SampleBudget& b_;
    BatchRunResult res_;
    const std::uint64_t bs_, total_, max_batches_;
    // Under MPI (core/distributed.h) every rank simulates the batches dealt to it (index %
    // ranks == rank) and rank 0 folds all of them in batch order: the same statistics as one
    // process. Rank 0 alone reads and writes the checkpoint and decides when to stop.
    const bool distributed_;
    const int rank_, ranks_;
    const bool root_;
    BatchAccumulator acc_;
    double resumed_seconds_ = 0.0;
    size_t tokens_ = 0;
    std::vector<std::unique_ptr<BatchWork>> pool_;
    tbb::concurrent_queue<BatchWork*> free_list_;
    Clock::time_point t0_, last_checkpoint_;
    std::atomic<bool> stop_flag_{false};
    std::uint64_t batches_at_start_ = 0;
    std::uint64_t next_ = 0;  // this rank's next batch
    InOrderFolds in_order_;   // rank 0 of a distributed run
    BatchSender sender_;      // a worker rank
};

}  // namespace

BatchRunResult run_batches(const BatchRunOptions& opt, const BatchFunction& simulate) {
    check_batch_options(opt);
    return BatchRun(opt, simulate).run();
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
