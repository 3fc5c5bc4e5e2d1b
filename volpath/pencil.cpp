#include "volpath/pencil.h"

#include "core/error.h"
#include "core/hash.h"
#include "core/rng.h"
#include "volpath/sampling.h"

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <limits>

namespace ssslab::volpath {

namespace {

// Bump when a change alters the numbers produced for a given seed.
constexpr const char* kEngineVersion = "volpath-pencil-3";

constexpr double kInf = std::numeric_limits<double>::infinity();

// One layer of the slab: its coefficients per tally channel (one channel in kPerChannel mode,
// three in kHero) and its place.
struct LayerSetup {
    WalkRegion region;
    double z0 = 0, z1 = kInf;  // [cm]
    double eta = 1;            // index of refraction
};

// Everything a path needs.
struct Setup {
    int nc = 1;
    std::vector<LayerSetup> layers;  // top first
    int first = 0;                   // the layer the beam enters (1 after a clear top layer)
    double eta_above = 1, eta_below = 1;
    double rsp = 0;
    double dr = 0;
    int nr = 0;
    PencilLayout layout;
    // Hero mode: probability of each channel to be the hero (the one-sample MIS weights use
    // them); uniform selection cycles R, G, B over the paths, otherwise a random draw.
    std::array<double, 3> hero_prob{1.0 / 3, 1.0 / 3, 1.0 / 3};
    bool hero_random = false;
    WalkRules rules;
};

double fresnel_normal(double n1, double n2) {
    const double r = (n1 - n2) / (n1 + n2);
    return r * r;
}

// Radial bin of an exit point (nr: beyond the grid).
std::size_t radial_bin(const Setup& s, const Vec3& p) {
    const double r = std::hypot(p.x, p.y);
    const double b = r / s.dr;
    return b < s.nr ? static_cast<std::size_t>(b) : static_cast<std::size_t>(s.nr);
}

// The walk's geometry: the layers as regions between planes z = z0 .. z1 (volpath/walk.h).
struct SlabGeometry {
    const Setup& s;
    bool multi_region = false;
    const WalkRegion& region(int i) const { return s.layers[static_cast<size_t>(i)].region; }
    template <int NC>
    WalkBoundary next(const WalkState<NC>& st) const {
        const LayerSetup& L = s.layers[static_cast<size_t>(st.region)];
        const Vec3& w = st.w;
        WalkBoundary b;
        b.t = w.z > 0 ? (L.z1 - st.p.z) / w.z : (w.z < 0 ? (L.z0 - st.p.z) / w.z : kInf);
        return b;
    }
    template <int NC>
    void arrive(WalkState<NC>& st, WalkBoundary& b) const {
        const LayerSetup& L = s.layers[static_cast<size_t>(st.region)];
        st.p += st.w * b.t;
        const bool up = st.w.z < 0;
        st.p.z = up ? L.z0 : L.z1;  // exactly on the plane
        b.n = {0, 0, up ? -1.0 : 1.0};
        st.on_surface = true;
    }
};

// What the pencil does with a walk: Fresnel and Snell at every interface, exits tallied into
// the radial bins of reflectance (and its single-scattering part) or transmittance.
template <int NC>
struct PencilHooks : TallyLostHooks<NC> {
    const Setup& s;
    // PencilLayout::lost(): the weight at risk and of paths given up.
    PencilHooks(const Setup& setup, double* t) : s(setup) {
        this->tally = t;
        this->stride = s.layout.per_channel();
        this->index = s.layout.lost();
    }

    BoundaryAction boundary(WalkState<NC>& st, const WalkBoundary&, RngStream& rng) {
        const int nlayers = static_cast<int>(s.layers.size());
        const LayerSetup& L = s.layers[static_cast<size_t>(st.region)];
        Vec3& w = st.w;
        const bool up = w.z < 0;
        const int next = up ? st.region - 1 : st.region + 1;
        const bool outside = next < 0 || next >= nlayers;
        const double n2 =
            outside ? (up ? s.eta_above : s.eta_below) : s.layers[static_cast<size_t>(next)].eta;
        // Inner interfaces between equal indices are crossed without a random number.
        const bool matched = !outside && n2 == L.eta;
        double cos_t = std::abs(w.z);
        const double F = matched ? 0.0 : fresnel_dielectric(std::abs(w.z), n2 / L.eta, cos_t);
        if (!matched && rng.uniform() < F) {
            w.z = -w.z;
            return BoundaryAction::kReflect;
        }
        if (outside) {  // the path leaves the slab
            const std::size_t bin = radial_bin(s, st.p);
            const PencilLayout& PL = s.layout;
            for (int c = 0; c < NC; ++c) {
                double* T = this->tally + static_cast<size_t>(c) * this->stride;
                const double b = st.weights.beta[c];
                if (up) {
                    T[PL.rd_r() + bin] += b;
                    T[PL.rd()] += b;
                    if (st.events == 1) {
                        T[PL.ss_r() + bin] += b;
                        T[PL.rd_ss()] += b;
                    }
                } else {
                    T[PL.tt_r() + bin] += b;
                    T[PL.tt()] += b;
                }
            }
            return BoundaryAction::kExit;
        }
        // Refraction into the next layer (Snell: the tangential part scales by n1 / n2).
        if (n2 != L.eta) {
            const double k = L.eta / n2;
            w = {w.x * k, w.y * k, up ? -cos_t : cos_t};
        }
        st.region = next;
        return BoundaryAction::kCross;
    }
};

// Trace one path from the entry point (hero channel `hero` in hero mode) through the one walk
// (volpath/walk.h); add its contributions to `tally` (NC channels of layout.per_channel()
// elements). Returns the number of scattering events.
template <int NC>
std::uint64_t trace(const Setup& s, RngStream& rng, int hero, double* tally) {
    WalkState<NC> st;
    st.weights.hero = hero;
    st.weights.prob = s.hero_prob;
    st.weights.start(1.0 - s.rsp);
    st.region = s.first;
    st.p = {0, 0, s.layers[static_cast<size_t>(s.first)].z0};
    st.w = {0, 0, 1};
    st.on_surface = true;
    const SlabGeometry geo{s, s.layers.size() > 1};
    PencilHooks<NC> hooks(s, tally);
    walk(geo, st, s.rules, rng, hooks);
    return static_cast<std::uint64_t>(st.events);
}

std::string fingerprint(const Medium& m, const PencilGrid& grid, const PencilOptions& o,
                        std::int64_t batch, int run) {
    ContentKey k("pencil-checkpoint");
    k.add("engine", kEngineVersion)
        .add("mode", to_string(o.mode))
        .add("absorption", to_string(o.absorption))
        .add("run", run)
        .add("seed", o.seed)
        .add("batch_paths", batch)
        .add("flight", static_cast<int>(o.flight))
        .add("hero_selection", static_cast<int>(o.hero_selection))
        .add("long_path_events", long_path_threshold(m, o, run < 3 ? run : -1))
        .add("long_path_survival", o.long_path_survival)
        .add("grid.dr_cm", grid.dr_cm)
        .add("grid.nr", grid.nr);
    add_to_key(k, "medium.", m);
    return k.text();
}

}  // namespace

const char* engine_version() {
    return kEngineVersion;
}

void ChannelRunControl::apply_run(BatchRunOptions& o, int run) const {
    apply(o);
    if (!checkpoint_prefix.empty())
        o.checkpoint_path =
            run_checkpoint_path(checkpoint_prefix, run == 3 ? "hero" : kChannelNames[run]);
    if (on_batch) o.on_batch = [this, run](const BatchProgress& p) { on_batch(run, p); };
    if (on_resume)
        o.on_resume = [this, run, path = o.checkpoint_path](const BatchProgress& p) {
            on_resume(run, p, path);
        };
}

BudgetQuantity least_precise_channel(
    std::size_t stride, int nc,
    std::function<std::size_t(const BatchAccumulator&, std::size_t block)> pick) {
    return [stride, nc, pick = std::move(pick)](const BatchAccumulator& acc, double& value,
                                                double& se) {
        double worst = -1;
        for (int c = 0; c < nc; ++c) {
            const std::size_t b = static_cast<std::size_t>(c) * stride;
            const std::size_t i = b + pick(acc, b);
            const double v = acc.mean(i), e = acc.standard_error(i);
            const double rel = v > 0 ? e / v : kInf;
            if (rel > worst) {
                worst = rel;
                value = v;
                se = e;
            }
        }
    };
}

const char* to_string(ChromaticMode m) {
    return m == ChromaticMode::kHero ? "hero" : "per-channel";
}

double PencilRun::mean(int c, std::size_t i) const {
    if (mode == ChromaticMode::kHero)
        return runs[0].mean[static_cast<size_t>(c) * layout.per_channel() + i];
    return runs[static_cast<size_t>(c)].mean[i];
}

double PencilRun::se(int c, std::size_t i) const {
    if (mode == ChromaticMode::kHero)
        return runs[0].se[static_cast<size_t>(c) * layout.per_channel() + i];
    return runs[static_cast<size_t>(c)].se[i];
}

void check_pencil(const Medium& m, const PencilGrid& grid) {
    if (!(grid.dr_cm > 0) || !std::isfinite(grid.dr_cm) || grid.nr < 1 || grid.nr > 10'000'000)
        throw std::invalid_argument("volpath: grid needs dr > 0 and 1 <= nr <= 1e7");
    if (!(m.eta_above > 0) || !(m.eta_below > 0))
        throw std::invalid_argument("volpath: indices of refraction must be positive");
    const std::vector<MediumLayer> layers = m.layers();
    for (size_t i = 0; i < layers.size(); ++i) {
        const MediumLayer& l = layers[i];
        const bool last = i + 1 == layers.size();
        const std::string where =
            layers.size() > 1 ? "volpath: layer " + std::to_string(i + 1) + ": " : "volpath: ";
        if (!(l.eta > 0))
            throw std::invalid_argument(where + "indices of refraction must be positive");
        if (!(l.thickness_cm > 0))
            throw std::invalid_argument(where + "thickness must be positive");
        if (!last && !(l.thickness_cm < 1e8))
            throw std::invalid_argument(where + "only the last layer may be quasi-infinite");
        const bool half_space = last && l.thickness_cm >= 1e8;
        for (int c = 0; c < 3; ++c) {
            const double a = l.sigma_a_per_cm[c], s = l.sigma_s_per_cm[c], g = l.g[c];
            if (!(a >= 0) || !(s >= 0) || !std::isfinite(a) || !std::isfinite(s))
                throw std::invalid_argument(where + "coefficients must be finite and >= 0");
            if (!(g > -1 && g < 1)) throw std::invalid_argument(where + "g must lie in (-1, 1)");
            if (half_space && a + s == 0)
                throw InfeasibleError(where + "channel " + kChannelNames[c] +
                                      " has sigma_t = 0 in a half-space: the beam never returns");
        }
    }
    // A clear top layer of a stack is entered as MCML enters it (its Rspecular(): the
    // reflections inside it at normal incidence are specular); that needs it clear in every
    // channel, so that the entry is the same for all.
    if (layers.size() > 1) {
        int clear = 0;
        for (int c = 0; c < 3; ++c) clear += layers[0].sigma_t(c) == 0.0;
        if (clear != 0 && clear != 3)
            throw std::invalid_argument(
                "volpath: the top layer of a stack must be clear in all channels or in none");
    }
}

std::int64_t long_path_threshold(const Medium& m, const PencilOptions& o, int channel) {
    if (o.long_path_events > 0) return o.long_path_events;
    double albedo = 0;
    for (const MediumLayer& l : m.layers())
        for (int c = 0; c < 3; ++c) {
            if (channel >= 0 && c != channel) continue;
            const double t = l.sigma_t(c);
            if (t > 0) albedo = std::max(albedo, l.sigma_s_per_cm[c] / t);
        }
    const double n = albedo < 1 ? 20.0 / (1.0 - albedo) : 1e6;
    return static_cast<std::int64_t>(std::clamp(std::ceil(n), 1e4, 1e6));
}

double entry_specular(const Medium& m) {
    double r1 = fresnel_normal(m.eta_above, m.eta);
    if (m.layered() && m.layers()[0].clear()) {
        // MCML's Rspecular(): the beam's reflections between the faces of a clear top layer.
        const double r2 = fresnel_normal(m.eta, m.lower_layers[0].eta);
        r1 = r1 + (1 - r1) * (1 - r1) * r2 / (1 - r1 * r2);
    }
    return r1;
}

void fill_profile(const BatchRunResult& r, std::size_t base, const PencilGrid& grid, int c,
                  double rsp, RadialProfile& p, bool single) {
    const PencilLayout L{grid.nr};
    if (r.mean.size() < base + L.per_channel())
        throw std::invalid_argument("volpath::fill_profile: result does not match the grid");
    const size_t off = base + (single ? L.ss_r() : L.rd_r());
    p.dr_cm = grid.dr_cm;
    p.nr = grid.nr;
    p.rd_per_cm2[c].resize(static_cast<size_t>(grid.nr));
    p.se_per_cm2[c].resize(static_cast<size_t>(grid.nr));
    for (int i = 0; i < grid.nr; ++i) {
        const double area = 2.0 * kPi * (i + 0.5) * grid.dr_cm * grid.dr_cm;
        p.rd_per_cm2[c][static_cast<size_t>(i)] = r.mean[off + static_cast<size_t>(i)] / area;
        p.se_per_cm2[c][static_cast<size_t>(i)] = r.se[off + static_cast<size_t>(i)] / area;
    }
    p.beyond[c] = r.mean[off + static_cast<size_t>(grid.nr)];
    p.beyond_se[c] = r.se[off + static_cast<size_t>(grid.nr)];
    const size_t total = base + (single ? L.rd_ss() : L.rd());
    p.rd_total[c] = r.mean[total];
    p.rd_total_se[c] = r.se[total];
    p.rsp[c] = rsp;
}

PencilRun simulate_pencil(const Medium& m, const PencilGrid& grid, const PencilOptions& o) {
    check_pencil(m, grid);
    PencilRun out;
    out.medium = m;
    out.grid = grid;
    out.mode = o.mode;
    out.layout.nr = grid.nr;

    SampleBudget budget = o.budget;
    if (!budget.any()) budget.samples = 1'000'000;
    std::int64_t batch = o.batch_paths;
    if (batch <= 0) batch = default_batch_samples(budget);
    if (o.mode == ChromaticMode::kHero) batch = (batch + 2) / 3 * 3;  // whole hero cycles

    Setup base;
    const std::vector<MediumLayer> layers = m.layers();
    {
        double z = 0;
        for (const MediumLayer& l : layers) {
            LayerSetup ls;
            ls.z0 = z;
            z = l.thickness_cm >= 1e8 ? kInf : z + l.thickness_cm;
            ls.z1 = z;
            ls.eta = l.eta;
            base.layers.push_back(ls);
        }
    }
    base.first = layers.size() > 1 && layers[0].clear() ? 1 : 0;
    base.eta_above = m.eta_above;
    base.eta_below = m.eta_below;
    base.rsp = entry_specular(m);
    base.dr = grid.dr_cm;
    base.nr = grid.nr;
    base.layout = out.layout;

    base.rules.long_survival = o.long_path_survival;
    base.rules.flight = o.flight;
    base.rules.absorption = o.absorption;

    const bool hero = o.mode == ChromaticMode::kHero;
    if (hero && o.only_channel >= 0)
        throw std::invalid_argument("volpath: only_channel needs the per-channel mode");
    if (o.only_channel > 2) throw std::invalid_argument("volpath: only_channel must be -1..2");
    const int nruns = hero ? 1 : 3;
    const std::size_t stride = out.layout.per_channel();
    out.runs.resize(static_cast<size_t>(nruns));
    for (int run = 0; run < nruns; ++run) {
        if (o.only_channel >= 0 && run != o.only_channel) continue;
        Setup s = base;
        s.nc = hero ? 3 : 1;
        s.rules.long_events = long_path_threshold(m, o, hero ? -1 : run);
        for (size_t k = 0; k < layers.size(); ++k) {
            std::array<double, 3> sigma_t{}, sigma_s{}, g{};
            for (int c = 0; c < s.nc; ++c) {
                const int mc = hero ? c : run;
                const size_t i = static_cast<size_t>(c);
                sigma_t[i] = layers[k].sigma_t(mc);
                sigma_s[i] = layers[k].sigma_s_per_cm[mc];
                g[i] = layers[k].g[mc];
            }
            s.layers[k].region = WalkRegion::make(sigma_t, sigma_s, g);
        }
        if (hero && o.hero_selection == HeroSelection::kMeanFreePath) {
            // Channels with a longer reduced mean free path spread further and need more paths
            // (those of the layer the beam enters).
            const MediumLayer& top = layers[static_cast<size_t>(base.first)];
            double sum = 0;
            for (int c = 0; c < 3; ++c) sum += s.hero_prob[static_cast<size_t>(c)] = top.mfp_cm(c);
            for (double& x : s.hero_prob) x /= sum;
            s.hero_random = true;
        }
        const int stream = hero ? 3 : run;

        BatchRunOptions bo;
        bo.tally_size = stride * static_cast<size_t>(s.nc);
        bo.batch_samples = batch;
        bo.budget = budget;
        bo.fingerprint = fingerprint(m, grid, o, batch, stream);
        o.apply_run(bo, stream);
        // Budget quantity: the least precise channel's larger of Rd and Tt.
        bo.quantity = least_precise_channel(
            stride, s.nc, [L = out.layout](const BatchAccumulator& acc, std::size_t b) {
                return acc.mean(b + L.rd()) >= acc.mean(b + L.tt()) ? L.rd() : L.tt();
            });

        const std::uint64_t seed = o.seed;
        const std::uint64_t bsz = static_cast<std::uint64_t>(batch);
        auto simulate = [&s, seed, stream, hero, bsz](std::uint64_t index, std::int64_t n,
                                                      double* tally) -> std::uint64_t {
            RngStream rng(seed, rng_domain::kVolpath + static_cast<std::uint32_t>(stream), index);
            std::uint64_t events = 0;
            for (std::int64_t i = 0; i < n; ++i) {
                if (hero) {
                    int h = static_cast<int>((index * bsz + static_cast<std::uint64_t>(i)) % 3);
                    if (s.hero_random) {
                        const double u = rng.uniform();
                        h = u < s.hero_prob[0] ? 0 : (u < s.hero_prob[0] + s.hero_prob[1] ? 1 : 2);
                    }
                    events += trace<3>(s, rng, h, tally);
                } else {
                    events += trace<1>(s, rng, 0, tally);
                }
            }
            return events;
        };
        out.runs[static_cast<size_t>(run)] = run_batches(bo, simulate);
        const BatchRunResult& r = out.runs[static_cast<size_t>(run)];
        out.seconds += r.seconds;
        out.paths += r.samples;
        out.events += r.work;
        if (r.reason == BatchStop::kInterrupted) {
            out.interrupted = true;
            return out;
        }
    }

    for (RadialProfile* p : {&out.profile, &out.single}) {
        p->name = m.name;
        p->dr_cm = grid.dr_cm;
        p->nr = grid.nr;
    }
    const PencilLayout& L = out.layout;
    for (int c = 0; c < 3; ++c) {
        if (o.only_channel >= 0 && c != o.only_channel) continue;
        const BatchRunResult& r = out.runs[hero ? 0 : static_cast<size_t>(c)];
        const size_t base_index = hero ? static_cast<size_t>(c) * stride : 0;
        fill_profile(r, base_index, grid, c, base.rsp, out.profile, false);
        fill_profile(r, base_index, grid, c, base.rsp, out.single, true);
        out.tt[c] = out.mean(c, L.tt());
        out.tt_se[c] = out.se(c, L.tt());
        out.lost[c] = out.mean(c, L.lost());
        out.lost_se[c] = out.se(c, L.lost());
    }
    return out;
}

}  // namespace ssslab::volpath
