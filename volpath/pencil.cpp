#include "volpath/pencil.h"

#include "core/error.h"
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

// Everything a path needs, per tally channel (one channel in kPerChannel mode, three in kHero).
struct Setup {
    int nc = 1;
    std::array<double, 3> sigma_t{}, sigma_s{}, albedo{}, g{};
    bool same_g = true;
    double thickness = kInf;          // [cm]
    double eta_top = 1, eta_bot = 1;  // outside index / medium index at the top and bottom
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
//   NC = 3 (weighted): hero channel `hero` samples; spectral MIS weights for all three.
template <int NC, bool kWeighted>
std::uint64_t trace(const Setup& s, RngStream& rng, int hero, double* tally) {
    static_assert(NC == 1 || (NC == 3 && kWeighted));
    constexpr bool kHeroMode = NC == 3;
    constexpr int nc = NC;
    const int h = kHeroMode ? hero : 0;
    // beta: the channel's path weight (contribution / sampling density of the hero's strategy,
    // times the MIS weight); q: the channels' sampling densities over the mean of all three.
    // Both are rescaled by mean(q) after every event, which leaves the balance-heuristic
    // estimate beta_k / mean(q) unchanged and keeps mean(q) = 1.
    double beta[NC], q[NC];
    for (int c = 0; c < nc; ++c) {
        beta[c] = 1.0 - s.rsp;
        q[c] = 1.0;
    }
    Vec3 p{0, 0, 0}, w{0, 0, 1};
    std::uint64_t events = 0;
    const double sigma_t = s.sigma_t[static_cast<size_t>(h)];

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
    // A flight of total length d through the medium ended at an interaction (scatter = true)
    // or at an exit. Hero mode: the densities of the three strategies for that flight.
    auto flight_weights = [&](double d, bool scatter) {
        if constexpr (kHeroMode) {
            for (int c = 0; c < 3; ++c) {
                const size_t i = static_cast<size_t>(c);
                const double e = c == h ? 1.0 : std::exp(-(s.sigma_t[i] - sigma_t) * d);
                if (scatter) {
                    q[c] *= s.sigma_t[i] / sigma_t * e;
                    beta[c] *= s.sigma_s[i] / sigma_t * e;
                } else {
                    q[c] *= e;
                    beta[c] *= e;
                }
            }
            rescale();
        } else if constexpr (kWeighted) {
            if (scatter) beta[0] *= s.albedo[0];
        }
    };

    for (;;) {
        double t = sigma_t > 0 ? -std::log(rng.uniform()) / sigma_t : kInf;
        double travelled = 0;
        bool exited = false;
        for (;;) {
            const double tb = w.z > 0 ? (s.thickness - p.z) / w.z : (w.z < 0 ? -p.z / w.z : kInf);
            if (t < tb) {
                p += w * t;
                travelled += t;
                break;
            }
            p += w * tb;
            travelled += tb;
            const bool top = w.z < 0;
            p.z = top ? 0.0 : s.thickness;
            const double F = fresnel_dielectric(std::abs(w.z), top ? s.eta_top : s.eta_bot);
            if (rng.uniform() < F) {
                w.z = -w.z;
                if (s.flight == FlightRule::kContinue) {
                    t -= tb;
                } else if (s.flight == FlightRule::kResample) {
                    t = sigma_t > 0 ? -std::log(rng.uniform()) / sigma_t : kInf;
                } else {  // kInteractAtBoundary: the interaction happens here
                    break;
                }
                continue;
            }
            // The path leaves the medium.
            flight_weights(travelled, false);
            const std::size_t bin = radial_bin(s, p);
            const PencilLayout& L = s.layout;
            const std::size_t stride = L.per_channel();
            for (int c = 0; c < nc; ++c) {
                double* T = tally + static_cast<size_t>(c) * stride;
                if (top) {
                    T[L.rd_r() + bin] += beta[c];
                    T[L.rd()] += beta[c];
                    if (events == 1) {
                        T[L.ss_r() + bin] += beta[c];
                        T[L.rd_ss()] += beta[c];
                    }
                } else {
                    T[L.tt_r() + bin] += beta[c];
                    T[L.tt()] += beta[c];
                }
            }
            exited = true;
            break;
        }
        if (exited) return events;

        // Interaction.
        ++events;
        if constexpr (kWeighted) {
            flight_weights(travelled, true);
            double m = beta[0];
            for (int c = 1; c < nc; ++c) m = std::max(m, beta[c]);
            if (m < kRouletteThreshold) {
                const double survive = m / kRouletteThreshold;
                if (!(rng.uniform() < survive)) return events;
                for (int c = 0; c < nc; ++c) beta[c] /= survive;
            }
        } else {
            if (!(rng.uniform() < s.albedo[0])) return events;  // absorbed
        }
        if (static_cast<std::int64_t>(events) > s.long_events) {
            if (static_cast<std::int64_t>(events) == s.long_events + 1)
                for (int c = 0; c < nc; ++c)
                    tally[static_cast<size_t>(c) * s.layout.per_channel() + s.layout.lost()] +=
                        beta[c];
            if (!(rng.uniform() < s.long_survival)) return events;
            for (int c = 0; c < nc; ++c) beta[c] /= s.long_survival;
        }
        const double g = s.g[static_cast<size_t>(h)];
        const double mu = sample_hg(g, rng.uniform());
        const double phi = 2.0 * kPi * rng.uniform();
        if constexpr (kHeroMode) {
            if (!s.same_g) {
                const double ph = hg_pdf(g, mu);
                for (int c = 0; c < 3; ++c) {
                    const double pc = hg_pdf(s.g[static_cast<size_t>(c)], mu) / ph;
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
    char buf[1024];
    std::snprintf(buf, sizeof buf,
                  "%s\nmode=%s absorption=%d run=%d seed=%" PRIu64 " batch=%" PRId64
                  " flight=%d hero_sel=%d long=%" PRId64 ",%.17g\ngrid=%.17g,%d\n",
                  kEngineVersion, to_string(o.mode), static_cast<int>(o.absorption), run, o.seed,
                  batch, static_cast<int>(o.flight), static_cast<int>(o.hero_selection),
                  long_path_threshold(m, o, run < 3 ? run : -1), o.long_path_survival, grid.dr_cm,
                  grid.nr);
    std::string s = buf;
    for (int c = 0; c < 3; ++c) {
        std::snprintf(buf, sizeof buf, "c%d %.17g %.17g %.17g\n", c, m.sigma_a_per_cm[c],
                      m.sigma_s_per_cm[c], m.g[c]);
        s += buf;
    }
    std::snprintf(buf, sizeof buf, "eta %.17g %.17g %.17g d %.17g\n", m.eta, m.eta_above,
                  m.eta_below, m.thickness_cm);
    return s + buf;
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
    if (!(m.eta > 0) || !(m.eta_above > 0) || !(m.eta_below > 0))
        throw std::invalid_argument("volpath: indices of refraction must be positive");
    if (!(m.thickness_cm > 0)) throw std::invalid_argument("volpath: thickness must be positive");
    const bool half_space = m.thickness_cm >= 1e8;
    for (int c = 0; c < 3; ++c) {
        const double a = m.sigma_a_per_cm[c], s = m.sigma_s_per_cm[c], g = m.g[c];
        if (!(a >= 0) || !(s >= 0) || !std::isfinite(a) || !std::isfinite(s))
            throw std::invalid_argument("volpath: coefficients must be finite and >= 0");
        if (!(g > -1 && g < 1)) throw std::invalid_argument("volpath: g must lie in (-1, 1)");
        if (half_space && a + s == 0)
            throw InfeasibleError(std::string("volpath: channel ") + kChannelNames[c] +
                                  " has sigma_t = 0 in a half-space: the beam never returns");
    }
}

std::int64_t long_path_threshold(const Medium& m, const PencilOptions& o, int channel) {
    if (o.long_path_events > 0) return o.long_path_events;
    double albedo = 0;
    for (int c = 0; c < 3; ++c) {
        if (channel >= 0 && c != channel) continue;
        const double t = m.sigma_a_per_cm[c] + m.sigma_s_per_cm[c];
        if (t > 0) albedo = std::max(albedo, m.sigma_s_per_cm[c] / t);
    }
    const double n = albedo < 1 ? 20.0 / (1.0 - albedo) : 1e6;
    return static_cast<std::int64_t>(std::clamp(std::ceil(n), 1e4, 1e6));
}

double entry_specular(const Medium& m) {
    return fresnel_normal(m.eta_above, m.eta);
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
    base.thickness = m.thickness_cm >= 1e8 ? kInf : m.thickness_cm;
    base.eta_top = m.eta_above / m.eta;
    base.eta_bot = m.eta_below / m.eta;
    base.rsp = fresnel_normal(m.eta_above, m.eta);
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
        for (int c = 0; c < s.nc; ++c) {
            const int mc = hero ? c : run;
            const size_t i = static_cast<size_t>(c);
            s.sigma_t[i] = m.sigma_a_per_cm[mc] + m.sigma_s_per_cm[mc];
            s.sigma_s[i] = m.sigma_s_per_cm[mc];
            s.albedo[i] = s.sigma_t[i] > 0 ? s.sigma_s[i] / s.sigma_t[i] : 0.0;
            s.g[i] = m.g[mc];
        }
        s.same_g = s.g[0] == s.g[1] && s.g[1] == s.g[2];
        if (hero && o.hero_selection == HeroSelection::kMeanFreePath) {
            // Channels with a longer reduced mean free path spread further and need more paths.
            double sum = 0;
            for (int c = 0; c < 3; ++c)
                sum += s.hero_prob[static_cast<size_t>(c)] =
                    1.0 / (m.sigma_a_per_cm[c] + m.sigma_s_per_cm[c] * (1 - m.g[c]));
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
                    events += trace<3, true>(s, rng, h, tally);
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
