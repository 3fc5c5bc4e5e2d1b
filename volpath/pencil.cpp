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
constexpr const char* kEngineVersion = "volpath-pencil-2";

constexpr double kInf = std::numeric_limits<double>::infinity();

// Russian roulette of the hero mode: a path whose largest channel weight falls below this
// survives with probability weight / kRouletteThreshold.
constexpr double kRouletteThreshold = 0.1;

// Interface hits within one free flight after which a path is given up (tallied as lost).
constexpr std::int64_t kMaxInterfaceHits = 1'000'000;

// One layer of the slab, per tally channel (one channel in kPerChannel mode, three in kHero).
struct LayerSetup {
    std::array<double, 3> sigma_t{}, sigma_s{}, albedo{}, g{};
    bool same_g = true;
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
    std::int64_t long_events = 0;
    // Hero mode: probability of each channel to be the hero (the one-sample MIS weights use
    // them); uniform selection cycles R, G, B over the paths, otherwise a random draw.
    std::array<double, 3> hero_prob{1.0 / 3, 1.0 / 3, 1.0 / 3};
    bool hero_random = false;
    double long_survival = 0.1;
    FlightRule flight = FlightRule::kContinue;
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

// Trace one path from the entry point; add its contributions to `tally` (NC channels of
// layout.per_channel() elements). Returns the number of scattering events.
//   NC = 1, !kWeighted: analog [Bitterli13 Alg. 1]: absorption by roulette with the albedo.
//   NC = 1, kWeighted: implicit absorption (the weight carries the albedo; Russian roulette).
//   NC = 3: hero channel `hero` samples; spectral MIS weights for all three channels.
//     kWeighted: the strategies are free paths and directions; absorption enters the weights,
//     Russian roulette bounds them from below.
//     !kWeighted (analog hero): each strategy also absorbs by roulette with its own albedo, so
//     a path's density under channel c is its contribution to c (equal phase functions): the
//     estimate (1 - Rsp) q_c / sum_k P(k) q_k is at most (1 - Rsp) / P(c), no roulette needed.
template <int NC, bool kWeighted>
std::uint64_t trace(const Setup& s, RngStream& rng, int hero, double* tally) {
    static_assert(NC == 1 || NC == 3);
    constexpr bool kHeroMode = NC == 3;
    constexpr int nc = NC;
    const int h = kHeroMode ? hero : 0;
    const size_t hi = static_cast<size_t>(h);
    const int nlayers = static_cast<int>(s.layers.size());
    // beta: the channel's path weight (contribution / sampling density of the hero's strategy,
    // times the MIS weight); q: the channels' sampling densities over the mean of all three.
    // Both are rescaled by mean(q) after every event, which leaves the balance-heuristic
    // estimate beta_k / mean(q) unchanged and keeps mean(q) = 1.
    double beta[NC], q[NC];
    for (int c = 0; c < nc; ++c) {
        beta[c] = 1.0 - s.rsp;
        q[c] = 1.0;
    }
    int li = s.first;  // the layer the path is in
    Vec3 p{0, 0, s.layers[static_cast<size_t>(li)].z0}, w{0, 0, 1};
    std::uint64_t events = 0;

    auto rescale = [&]() {
        if constexpr (kHeroMode) {
            const double m = s.hero_prob[0] * q[0] + s.hero_prob[1] * q[1] + s.hero_prob[2] * q[2];
            const double inv = 1.0 / m;
            for (int c = 0; c < 3; ++c) {
                q[c] *= inv;
                beta[c] *= inv;
            }
        }
    };
    // Hero mode: (sigma_t of channel c - sigma_t of the hero) x distance, summed over the
    // layers the flight crossed; the flight's densities differ between the channels by
    // exp(-dod[c]).
    double dod[NC];
    // A flight ended at an interaction in layer L (scatter = true) or at an exit, after `d` in
    // its last layer. Hero mode: the densities of the three strategies for that flight.
    auto flight_weights = [&](const LayerSetup& L, double d, bool scatter) {
        if constexpr (kHeroMode) {
            const double sigma_t = L.sigma_t[hi];
            for (int c = 0; c < 3; ++c) {
                const size_t i = static_cast<size_t>(c);
                const double e = c == h ? 1.0 : std::exp(-(dod[c] + (L.sigma_t[i] - sigma_t) * d));
                if (scatter && !kWeighted) {  // survived the hero's absorption roulette
                    const double f = L.sigma_s[i] / L.sigma_s[hi] * e;
                    q[c] *= f;
                    beta[c] *= f;
                } else if (scatter) {
                    q[c] *= L.sigma_t[i] / sigma_t * e;
                    beta[c] *= L.sigma_s[i] / sigma_t * e;
                } else {
                    q[c] *= e;
                    beta[c] *= e;
                }
            }
            rescale();
        } else if constexpr (kWeighted) {
            if (scatter) beta[0] *= L.albedo[0];
        }
    };

    for (;;) {
        // The free path is sampled as an optical depth (of the hero channel) and consumed layer
        // by layer: t is what is left of it as a distance in the current layer, or, in a layer
        // that does not attenuate (t infinite), `held` keeps it as optical depth.
        const LayerSetup* L = &s.layers[static_cast<size_t>(li)];
        double t = kInf, held = 0;
        auto sample_flight = [&]() {
            t = kInf;
            held = 0;
            if (L->sigma_t[hi] > 0)
                t = -std::log(rng.uniform()) / L->sigma_t[hi];
            else if (nlayers > 1)
                held = -std::log(rng.uniform());
        };
        sample_flight();
        double travelled = 0;  // in the current layer
        for (int c = 0; c < nc; ++c) dod[c] = 0;
        bool exited = false;
        for (std::int64_t hits = 0;; ++hits) {
            // Snell's invariant n sin(theta) keeps a path from being trapped between interfaces
            // (it can always go back where it came from); this bounds the loop against rounding.
            if (hits > kMaxInterfaceHits) {
                for (int c = 0; c < nc; ++c)
                    tally[static_cast<size_t>(c) * s.layout.per_channel() + s.layout.lost()] +=
                        beta[c];
                return events;
            }
            const double tb =
                w.z > 0 ? (L->z1 - p.z) / w.z : (w.z < 0 ? (L->z0 - p.z) / w.z : kInf);
            if (t < tb) {
                p += w * t;
                travelled += t;
                break;
            }
            p += w * tb;
            travelled += tb;
            const bool up = w.z < 0;
            p.z = up ? L->z0 : L->z1;
            const int next = up ? li - 1 : li + 1;
            const bool outside = next < 0 || next >= nlayers;
            const double n2 = outside ? (up ? s.eta_above : s.eta_below)
                                      : s.layers[static_cast<size_t>(next)].eta;
            // Inner interfaces between equal indices are crossed without a random number.
            const bool matched = !outside && n2 == L->eta;
            double cos_t = std::abs(w.z);
            const double F = matched ? 0.0 : fresnel_dielectric(std::abs(w.z), n2 / L->eta, cos_t);
            if (!matched && rng.uniform() < F) {
                w.z = -w.z;
                if (s.flight == FlightRule::kContinue) {
                    t -= tb;
                } else if (s.flight == FlightRule::kResample) {
                    sample_flight();
                } else {  // kInteractAtBoundary: the interaction happens here
                    break;
                }
                continue;
            }
            if (outside) {  // the path leaves the slab
                flight_weights(*L, travelled, false);
                const std::size_t bin = radial_bin(s, p);
                const PencilLayout& PL = s.layout;
                const std::size_t stride = PL.per_channel();
                for (int c = 0; c < nc; ++c) {
                    double* T = tally + static_cast<size_t>(c) * stride;
                    if (up) {
                        T[PL.rd_r() + bin] += beta[c];
                        T[PL.rd()] += beta[c];
                        if (events == 1) {
                            T[PL.ss_r() + bin] += beta[c];
                            T[PL.rd_ss()] += beta[c];
                        }
                    } else {
                        T[PL.tt_r() + bin] += beta[c];
                        T[PL.tt()] += beta[c];
                    }
                }
                exited = true;
                break;
            }
            // Refraction into the next layer (Snell: the tangential part scales by n1 / n2);
            // the rest of the free path goes with it as optical depth.
            if (n2 != L->eta) {
                const double k = L->eta / n2;
                w = {w.x * k, w.y * k, up ? -cos_t : cos_t};
            }
            const double tau = L->sigma_t[hi] > 0 ? (t - tb) * L->sigma_t[hi] : held;
            if constexpr (kHeroMode)
                for (int c = 0; c < 3; ++c)
                    dod[c] += (L->sigma_t[static_cast<size_t>(c)] - L->sigma_t[hi]) * travelled;
            travelled = 0;
            li = next;
            L = &s.layers[static_cast<size_t>(li)];
            t = L->sigma_t[hi] > 0 ? tau / L->sigma_t[hi] : kInf;
            held = L->sigma_t[hi] > 0 ? 0.0 : tau;
        }
        if (exited) return events;

        // Interaction in layer L.
        ++events;
        if constexpr (kWeighted) {
            flight_weights(*L, travelled, true);
            double m = beta[0];
            for (int c = 1; c < nc; ++c) m = std::max(m, beta[c]);
            if (m < kRouletteThreshold) {
                const double survive = m / kRouletteThreshold;
                if (!(rng.uniform() < survive)) return events;
                for (int c = 0; c < nc; ++c) beta[c] /= survive;
            }
        } else {
            if (!(rng.uniform() < L->albedo[hi])) return events;  // absorbed
            if constexpr (kHeroMode) flight_weights(*L, travelled, true);
        }
        if (static_cast<std::int64_t>(events) > s.long_events) {
            if (static_cast<std::int64_t>(events) == s.long_events + 1)
                for (int c = 0; c < nc; ++c)
                    tally[static_cast<size_t>(c) * s.layout.per_channel() + s.layout.lost()] +=
                        beta[c];
            if (!(rng.uniform() < s.long_survival)) return events;
            for (int c = 0; c < nc; ++c) beta[c] /= s.long_survival;
        }
        const double g = L->g[hi];
        const double mu = sample_hg(g, rng.uniform());
        const double phi = 2.0 * kPi * rng.uniform();
        if constexpr (kHeroMode) {
            if (!L->same_g) {
                const double ph = hg_pdf(g, mu);
                for (int c = 0; c < 3; ++c) {
                    const double pc = hg_pdf(L->g[static_cast<size_t>(c)], mu) / ph;
                    q[c] *= pc;
                    beta[c] *= pc;
                }
                rescale();
            }
        }
        w = rotate(w, mu, phi);
    }
}

std::string fingerprint(const Medium& m, const PencilGrid& grid, const PencilOptions& o,
                        std::int64_t batch, int run) {
    ContentKey k("pencil-checkpoint");
    k.add("engine", kEngineVersion)
        .add("mode", to_string(o.mode))
        .add("absorption", o.absorption == Absorption::kWeighted ? "weighted" : "analog")
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
    if (batch <= 0)
        batch = budget.samples && !budget.seconds && !budget.rel_error
                    ? std::max<std::int64_t>(1000, (*budget.samples + 999) / 1000)
                    : 1000;
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

    base.long_survival = o.long_path_survival;
    base.flight = o.flight;

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
        s.long_events = long_path_threshold(m, o, hero ? -1 : run);
        for (size_t k = 0; k < layers.size(); ++k) {
            LayerSetup& ls = s.layers[k];
            for (int c = 0; c < s.nc; ++c) {
                const int mc = hero ? c : run;
                const size_t i = static_cast<size_t>(c);
                ls.sigma_t[i] = layers[k].sigma_t(mc);
                ls.sigma_s[i] = layers[k].sigma_s_per_cm[mc];
                ls.albedo[i] = ls.sigma_t[i] > 0 ? ls.sigma_s[i] / ls.sigma_t[i] : 0.0;
                ls.g[i] = layers[k].g[mc];
            }
            ls.same_g = ls.g[0] == ls.g[1] && ls.g[1] == ls.g[2];
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
        bo.threads = o.threads;
        bo.fingerprint = fingerprint(m, grid, o, batch, stream);
        if (!o.checkpoint_prefix.empty())
            bo.checkpoint_path =
                o.checkpoint_prefix + "." + (hero ? "hero" : kChannelNames[run]) + ".ckpt";
        bo.checkpoint_seconds = o.checkpoint_seconds;
        bo.cancel = o.cancel;
        bo.snapshots = o.snapshots;
        const PencilLayout L = out.layout;
        const int nc = s.nc;
        // Budget quantity: the least precise channel's larger of Rd and Tt.
        bo.quantity = [L, stride, nc](const BatchAccumulator& acc, double& value, double& se) {
            double worst = -1;
            for (int c = 0; c < nc; ++c) {
                const size_t b = static_cast<size_t>(c) * stride;
                const double rd = acc.mean(b + L.rd()), tt = acc.mean(b + L.tt());
                const size_t i = b + (rd >= tt ? L.rd() : L.tt());
                const double v = acc.mean(i), e = acc.standard_error(i);
                const double rel = v > 0 ? e / v : kInf;
                if (rel > worst) {
                    worst = rel;
                    value = v;
                    se = e;
                }
            }
        };
        if (o.on_batch)
            bo.on_batch = [&o, stream](const BatchProgress& p) { o.on_batch(stream, p); };
        if (o.on_resume)
            bo.on_resume = [&o, stream, path = bo.checkpoint_path](const BatchProgress& p) {
                o.on_resume(stream, p, path);
            };
        bo.fresh = o.fresh;

        const std::uint64_t seed = o.seed;
        const bool weighted = o.absorption == Absorption::kWeighted;
        const std::uint64_t bsz = static_cast<std::uint64_t>(batch);
        auto simulate = [&s, seed, stream, hero, weighted, bsz](std::uint64_t index, std::int64_t n,
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
                    events += weighted ? trace<3, true>(s, rng, h, tally)
                                       : trace<3, false>(s, rng, h, tally);
                } else if (weighted) {
                    events += trace<1, true>(s, rng, 0, tally);
                } else {
                    events += trace<1, false>(s, rng, 0, tally);
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
