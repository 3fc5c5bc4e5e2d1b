// The one random walk of the path tracer inside a medium [Bitterli13 Alg. 1, §3.2]: every engine
// (the pencil's layered slab, the lit sphere, media inside meshes, the scene renderer) runs
// this loop and differs only in its geometry and in what it does at a boundary, a scattering
// vertex and an exit (the hooks).
//
// - Geometry: regions (a slab's layers; the sphere's or a mesh's inside) and the distance to
//   the next boundary along the path. Free paths are sampled as the hero channel's optical
//   depth and carried across region boundaries (a clear region holds it).
// - Heterogeneous regions (a density grid) are tracked by delta tracking against the majorant
//   sigma_t max(d); a tentative collision is real with probability d(x) / max(d).
// - Weights (`SpectralWeights`): one path for RGB with a hero channel that samples, and every
//   channel's weight carries the one-sample balance-heuristic MIS weight over the three
//   channels' sampling densities (spectral MIS, as pbrt-v4 and Mitsuba 3 do); or one channel
//   (NC = 1, per-channel runs).
// - Absorption (`Absorption`, one policy per estimator): analog (the hero's roulette with its
//   albedo; each channel's strategy includes its own roulette, so the weights stay below
//   1 / P(hero = c)) or weighted (the albedo in the weights, Russian roulette below 0.1), or
//   per channel (each channel's strategy weighted where its albedo is at least 0.5, analog
//   below; the hero's policy decides at a collision).
// - Long paths: after `long_events` scattering events a path survives each further one with
//   probability `long_survival` [Bitterli13 §3.2]; the weight reaching the first round (the
//   mass at risk) goes to the `at_risk` hook. A flight that hits boundaries 10^6 times is
//   given up (`lost`).
//
// Random-number order (what the engines' golden-seed tests pin): a flight's free path, then per
// tentative collision the null test (heterogeneous only), per boundary hit what the boundary
// hook draws, per collision the absorption roulette (weighted: the Russian roulette, when
// below the threshold), the long-path roulette, the phase function's cosine and azimuth.
#pragma once

#include "core/enum_names.h"
#include "core/rng.h"
#include "core/vec3.h"
#include "volpath/density_grid.h"
#include "volpath/sampling.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace ssslab::volpath {

/// How absorption enters a run.
enum class Absorption {
    /// Absorb by roulette with the single-scattering albedo; weights stay 1 [Bitterli13 Alg. 1].
    kAnalog,
    /// Multiply the weight by the albedo at every interaction and end paths by Russian roulette
    /// when the weight falls below 0.1 (implicit capture, as MCML does with its own threshold).
    kWeighted,
    /// Each channel's strategy by its own albedo: weighted where it is at least
    /// kPerChannelWeightedAlbedo, analog below; at a collision the hero's policy acts, and the
    /// densities of the one-sample MIS are each channel's own (SpectralWeights::scatter). In a
    /// medium of one high and two low albedos (a ketchup: 0.75, 0.067, 0.02) the high
    /// channel's walks then collect light past the absorptions that would end them, while the
    /// low channels keep the analog walk's short paths.
    kPerChannel,
};

/// The albedo from which a channel's strategy weights its absorption under kPerChannel.
inline constexpr double kPerChannelWeightedAlbedo = 0.5;

/// Channel c's own policy under `a` in a region of these albedos (kAnalog or kWeighted).
inline Absorption channel_absorption(Absorption a, double albedo) {
    if (a != Absorption::kPerChannel) return a;
    return albedo >= kPerChannelWeightedAlbedo ? Absorption::kWeighted : Absorption::kAnalog;
}

}  // namespace ssslab::volpath
template <>
struct ssslab::EnumNames<ssslab::volpath::Absorption> {
    using E = ssslab::volpath::Absorption;
    static constexpr std::array<std::pair<E, std::string_view>, 3> table = {
        {{E::kAnalog, "analog"}, {E::kWeighted, "weighted"}, {E::kPerChannel, "per-channel"}}};
};
namespace ssslab::volpath {

/// "analog", "weighted" or "per-channel": the policy's name in keys, settings and reports.
inline const char* to_string(Absorption a) {
    return name_of(a).data();
}

/// What happens to the sampled free path when it reaches the boundary and is reflected.
enum class FlightRule {
    /// Travel the rest of the sampled free path after the reflection [Bitterli13 Alg. 1, line 8].
    kContinue,
    /// Draw a fresh free path from the reflection point. Unbiased as well (the exponential
    /// distribution is memoryless).
    kResample,
    /// Interact (absorb or scatter) at the reflection point: biased; for the tests that show
    /// the boundary treatment matters.
    kInteractAtBoundary,
};

/// The coefficients of one region of a medium, per tally channel (index 0 only for a
/// per-channel walk) [1 / length unit of the geometry].
struct WalkRegion {
    std::array<double, 3> sigma_t{}, sigma_s{}, albedo{}, g{};
    bool same_g = true;
    /// Heterogeneous: sigma_t and sigma_s are scaled by this density (null: 1).
    const DensityGrid* density = nullptr;
    /// sigma_t max(d): the majorants free paths are sampled with (sigma_t when homogeneous).
    std::array<double, 3> majorant{};

    /// A region of these coefficients (albedo, same_g and the majorants derived).
    static WalkRegion make(const std::array<double, 3>& sigma_t,
                           const std::array<double, 3>& sigma_s, const std::array<double, 3>& g,
                           const DensityGrid* density = nullptr) {
        WalkRegion r;
        r.sigma_t = sigma_t;
        r.sigma_s = sigma_s;
        r.g = g;
        r.density = density;
        const double dmax = density ? density->max_density() : 1.0;
        for (std::size_t c = 0; c < 3; ++c) {
            r.albedo[c] = sigma_t[c] > 0 ? sigma_s[c] / sigma_t[c] : 0.0;
            r.majorant[c] = sigma_t[c] * dmax;
        }
        r.same_g = g[0] == g[1] && g[1] == g[2];
        return r;
    }
};

/// A path's channel weights. beta: the channel's contribution over the hero's sampling density
/// times its MIS weight; q: the channels' sampling densities relative to their mixture. Both
/// are rescaled by the mixture sum_k P(k) q_k after every event, which leaves the
/// balance-heuristic estimate unchanged and keeps the mixture at 1 [Bitterli13 §3.2 for the
/// weights of a single channel]. NC = 1: beta only.
template <int NC>
struct SpectralWeights {
    static_assert(NC == 1 || NC == 3);
    double beta[NC], q[NC];
    int hero = 0;
    /// Probability of each channel to be the hero (NC = 3).
    std::array<double, 3> prob{1.0 / 3, 1.0 / 3, 1.0 / 3};

    void start(double b) {
        for (int c = 0; c < NC; ++c) {
            beta[c] = b;
            q[c] = 1.0;
        }
    }
    /// A new hero for the rest of the path (NC = 3), drawn with probabilities `p` (summing to
    /// one) by the inverse of their distribution at u in [0, 1): the balance-heuristic MIS
    /// starts afresh (every q = 1), which is the one-sample MIS of the walk from here on over
    /// the mixture sum_k p_k (channel k's density), unbiased given what came before whatever p
    /// is, so p may depend on the path so far (as Cycles chooses its channel by throughput x
    /// albedo at every step).
    void choose_hero(const std::array<double, 3>& p, double u) {
        if constexpr (NC == 3) {
            prob = p;
            hero = 0;
            for (double cdf = p[0]; hero < 2 && !(u < cdf);)
                cdf += p[static_cast<std::size_t>(++hero)];
            // Rounding may leave u past the sum: the last channel that can be chosen.
            while (p[static_cast<std::size_t>(hero)] <= 0) --hero;
            for (int c = 0; c < 3; ++c) q[c] = 1.0;
        }
    }
    /// choose_hero with probabilities proportional to each channel's weight times `albedo`
    /// (uniform if they are all 0).
    void choose_hero_by_throughput(const std::array<double, 3>& albedo, double u) {
        if constexpr (NC == 3) choose_hero(throughput_probabilities(albedo), u);
    }
    /// The probabilities choose_hero_by_throughput draws with.
    std::array<double, 3> throughput_probabilities(const std::array<double, 3>& albedo) const {
        std::array<double, 3> p{};
        double sum = 0;
        for (std::size_t c = 0; c < 3; ++c)
            sum += p[c] = beta[std::min<std::size_t>(c, NC - 1)] * albedo[c];
        if (sum > 0)
            for (double& v : p) v /= sum;
        else
            p = {1.0 / 3, 1.0 / 3, 1.0 / 3};
        return p;
    }
    double max_beta() const {
        double m = beta[0];
        for (int c = 1; c < NC; ++c) m = std::max(m, beta[c]);
        return m;
    }
    /// A roulette's survivor: the weights divided by the survival probability.
    void survived(double p) {
        for (int c = 0; c < NC; ++c) beta[c] /= p;
    }
    void rescale() {
        if constexpr (NC == 3) {
            const double inv = 1.0 / (prob[0] * q[0] + prob[1] * q[1] + prob[2] * q[2]);
            for (int c = 0; c < 3; ++c) {
                q[c] *= inv;
                beta[c] *= inv;
            }
        }
    }
    /// Channel c's transmittance over d relative to the hero's.
    double relative_transmittance(const WalkRegion& r, int c, double d) const {
        const std::size_t i = static_cast<std::size_t>(c), h = static_cast<std::size_t>(hero);
        return c == hero ? 1.0 : std::exp(-(r.majorant[i] - r.majorant[h]) * d);
    }
    /// A flight of length d that met no collision (it reached a boundary).
    void pass(const WalkRegion& r, double d) {
        if constexpr (NC == 3) {
            for (int c = 0; c < 3; ++c) {
                const double e = relative_transmittance(r, c, d);
                q[c] *= e;
                beta[c] *= e;
            }
            rescale();
        }
    }
    /// A flight of length d ended at a null collision (same null probability for all channels;
    /// their densities of a tentative collision differ by their majorants).
    void null_collision(const WalkRegion& r, double d) {
        if constexpr (NC == 3) {
            const std::size_t h = static_cast<std::size_t>(hero);
            for (int c = 0; c < 3; ++c) {
                const std::size_t i = static_cast<std::size_t>(c);
                const double f = c == hero ? 1.0
                                           : r.majorant[i] / r.majorant[h] *
                                                 std::exp(-(r.majorant[i] - r.majorant[h]) * d);
                q[c] *= f;
                beta[c] *= f;
            }
            rescale();
        }
    }
    /// A flight of length d ended at a collision that scatters. Analog: the hero survived its
    /// absorption roulette, and each channel's strategy includes its own. Weighted: absorption
    /// enters the weights.
    /// Under kPerChannel each channel's strategy has its own: the density of a scattering
    /// collision at d is sigma_s T for an analog strategy (its roulette survived), sigma_t T
    /// for a weighted one.
    void scatter(const WalkRegion& r, double d, Absorption a) {
        if constexpr (NC == 3) {
            const std::size_t h = static_cast<std::size_t>(hero);
            const auto density = [&](std::size_t i) {
                return channel_absorption(a, r.albedo[i]) == Absorption::kAnalog ? r.sigma_s[i]
                                                                                 : r.sigma_t[i];
            };
            const double dh = density(h);
            for (int c = 0; c < 3; ++c) {
                const std::size_t i = static_cast<std::size_t>(c);
                const double e = relative_transmittance(r, c, d);
                q[c] *= density(i) / dh * e;
                beta[c] *= r.sigma_s[i] / dh * e;
            }
            rescale();
        } else if (channel_absorption(a, r.albedo[0]) == Absorption::kWeighted) {
            beta[0] *= r.albedo[0];
        }
    }
    /// The hero's phase function sampled the cosine mu.
    void phase(const WalkRegion& r, double mu) {
        if constexpr (NC == 3) {
            if (r.same_g) return;
            const double ph = hg_pdf(r.g[static_cast<std::size_t>(hero)], mu);
            for (int c = 0; c < 3; ++c) {
                const double f = hg_pdf(r.g[static_cast<std::size_t>(c)], mu) / ph;
                q[c] *= f;
                beta[c] *= f;
            }
            rescale();
        }
    }
};

/// Where a walk is: position, direction, region, weights, and its counts.
template <int NC>
struct WalkState {
    Vec3 p, w;
    int region = 0;
    /// p lies on a boundary (ray queries skip the surface it is on).
    bool on_surface = false;
    SpectralWeights<NC> weights;
    std::int64_t events = 0;    ///< scattering events
    std::uint64_t queries = 0;  ///< ray queries (mesh geometry)
};

/// The next boundary along a path, as a geometry reports it.
struct WalkBoundary {
    double t = std::numeric_limits<double>::infinity();  ///< distance
    Vec3 n;  ///< unit normal pointing out of the current region (by `next` or `arrive`)
    enum class Kind {
        kFace,  ///< a boundary of the region
        kSlip,  ///< the path slipped across a crease and met the boundary from outside within a
                ///< few epsilons: it is inside, crosses back and goes on (mesh geometry)
        kWrongSide,  ///< met from outside farther than that: lost if the path gets there
        kLeak,       ///< no boundary (a leak) or another shape: the walk is lost
    } kind = Kind::kFace;
    std::uint32_t shape = 0;     ///< mesh geometry: the shape met
    std::uint32_t triangle = 0;  ///< and its triangle
};

/// What a boundary hook decided.
enum class BoundaryAction {
    kReflect,  ///< the path stays in the region with a new direction (s.w)
    kCross,    ///< the path went on into region s.region (its direction s.w)
    kExit,     ///< the path left the medium (the hook tallied it): the walk ends
    kEnd,      ///< the path ended at the boundary (a roulette, a depth limit)
};

enum class WalkEnd { kExited, kAbsorbed, kLost };

struct WalkRules {
    Absorption absorption = Absorption::kAnalog;
    FlightRule flight = FlightRule::kContinue;
    std::int64_t long_events = 1'000'000;
    double long_survival = 0.1;
};

/// Hooks an engine may leave out: the defaults do nothing.
struct WalkHooks {
    /// Whether NEE is done at this scattering vertex; the analog absorption roulette then waits
    /// until after `at_vertex`, which gets the survival probability to carry instead (weighted
    /// absorption: `at_vertex` before the roulette on the weights, survival 1).
    template <class S>
    bool vertex_nee(const S&) const {
        return false;
    }
    template <class S>
    void at_vertex(S&, double /*survive*/, RngStream&) {}
    /// After the phase function's cosine was sampled, before its weights are applied.
    template <class S>
    void scattered(const S&, double /*mu*/) {}
    /// The weights of a path reaching the long-path roulette's first round.
    template <class S>
    void at_risk(const S&) {}
    /// The weights of a path given up (a leak or a trapped flight).
    template <class S>
    void lost(const S&) {}
};

/// Hooks of the engines that tally the weight at risk at the long-path roulette and the weight
/// of lost paths into one element per channel of their tally (`index`, channels `stride`
/// apart).
template <int NC>
struct TallyLostHooks : WalkHooks {
    double* tally = nullptr;
    std::size_t stride = 0, index = 0;
    void add_lost(const WalkState<NC>& s) {
        for (int c = 0; c < NC; ++c)
            tally[static_cast<std::size_t>(c) * stride + index] += s.weights.beta[c];
    }
    void at_risk(const WalkState<NC>& s) { add_lost(s); }
    void lost(const WalkState<NC>& s) { add_lost(s); }
};

/// Interface hits within one free flight after which a path is given up: Snell's invariant
/// keeps a path from being trapped between interfaces, so only rounding (a whispering-gallery
/// orbit made exactly tangent) gets there.
inline constexpr std::int64_t kMaxBoundaryHits = 1'000'000;

/// Russian roulette of the weighted estimators: a path whose largest channel weight falls
/// below this survives with probability weight / threshold.
inline constexpr double kWeightRouletteThreshold = 0.1;

/// The walk from s (inside region s.region, or on its boundary going in) until the path leaves
/// the medium, is absorbed or is lost. Geometry: `region(i)` (const WalkRegion&),
/// `multi_region` (bool: a clear region holds the free path), `next(s)` (WalkBoundary: the
/// next boundary along s.w, counting s.queries), `arrive(s, b)` (moves s.p onto the
/// boundary b, sets b.n, s.on_surface) and optionally `clear(s, t)` (true only if the segment
/// of length t from s.p along s.w meets no boundary). Hooks: `boundary(s, b, rng)` (BoundaryAction)
/// and those of WalkHooks.
template <int NC, class Geometry, class Hooks>
WalkEnd walk(const Geometry& geo, WalkState<NC>& s, const WalkRules& rules, RngStream& rng,
             Hooks& hooks) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    SpectralWeights<NC>& wt = s.weights;
    const std::size_t h = static_cast<std::size_t>(NC == 3 ? wt.hero : 0);
    for (;;) {
        const WalkRegion* R = &geo.region(s.region);
        double st = R->majorant[h];
        // t: what is left of the free path as a distance in the current region; in a region
        // that does not attenuate (t infinite) `held` keeps it as optical depth.
        double t = kInf, held = 0;
        auto sample = [&] {
            t = kInf;
            held = 0;
            if (st > 0)
                t = -std::log(rng.uniform()) / st;
            else if (geo.multi_region)
                held = -std::log(rng.uniform());
        };
        sample();
        double travelled = 0;  // since the flight or the last boundary
        for (std::int64_t hits = 0;;) {
            // A geometry may know that the flight's segment stays clear of every boundary
            // (`clear`): then the collision comes first without a query, as the query would
            // have said.
            bool collide = false;
            WalkBoundary b;
            if constexpr (requires { geo.clear(s, t); }) collide = t < kInf && geo.clear(s, t);
            if (!collide) {
                b = geo.next(s);
                if (b.kind == WalkBoundary::Kind::kLeak) {
                    hooks.lost(s);
                    return WalkEnd::kLost;
                }
                collide = t < b.t;
            }
            if (collide) {
                s.p += s.w * t;
                travelled += t;
                s.on_surface = false;
                if (R->density &&
                    !(rng.uniform() * R->density->max_density() < R->density->density(s.p))) {
                    wt.null_collision(*R, travelled);
                    travelled = 0;
                    t = -std::log(rng.uniform()) / st;
                    continue;
                }
                break;
            }
            geo.arrive(s, b);
            travelled += b.t;
            const double rest = t - b.t;
            if (b.kind == WalkBoundary::Kind::kSlip) {
                t = rest;
                continue;
            }
            if (b.kind == WalkBoundary::Kind::kWrongSide) {
                hooks.lost(s);
                return WalkEnd::kLost;
            }
            if (++hits > kMaxBoundaryHits) {
                hooks.lost(s);
                return WalkEnd::kLost;
            }
            wt.pass(*R, travelled);
            travelled = 0;
            const BoundaryAction a = hooks.boundary(s, b, rng);
            if (a == BoundaryAction::kExit) return WalkEnd::kExited;
            if (a == BoundaryAction::kEnd) return WalkEnd::kAbsorbed;
            if (a == BoundaryAction::kCross) {
                // The rest of the free path goes on as optical depth.
                const double tau = st > 0 ? rest * st : held;
                R = &geo.region(s.region);
                st = R->majorant[h];
                t = st > 0 ? tau / st : kInf;
                held = st > 0 ? 0.0 : tau;
                continue;
            }
            if (rules.flight == FlightRule::kContinue) {
                t = rest;
            } else if (rules.flight == FlightRule::kResample) {
                sample();
            } else {
                break;  // kInteractAtBoundary: the collision happens here
            }
        }

        // A collision in R at s.p; the hero's policy acts (kPerChannel: its own).
        ++s.events;
        const Absorption absorption = channel_absorption(rules.absorption, R->albedo[h]);
        if (absorption == Absorption::kWeighted) {
            wt.scatter(*R, travelled, rules.absorption);
            // NEE with the weights that hold the albedo, before the roulette on them (after
            // it, a strongly absorbing medium would collect light at the few survivors only).
            if (hooks.vertex_nee(s)) hooks.at_vertex(s, 1.0, rng);
            const double m = wt.max_beta();
            if (m < kWeightRouletteThreshold) {
                const double survive = m / kWeightRouletteThreshold;
                if (!(rng.uniform() < survive)) return WalkEnd::kAbsorbed;
                wt.survived(survive);
            }
        }
        const double survive = R->albedo[h];
        const bool defer = absorption == Absorption::kAnalog && hooks.vertex_nee(s);
        if (absorption == Absorption::kAnalog) {
            if (!defer && !(rng.uniform() < survive)) return WalkEnd::kAbsorbed;
            wt.scatter(*R, travelled, rules.absorption);
        }
        if (s.events > rules.long_events) {
            if (s.events == rules.long_events + 1) hooks.at_risk(s);
            if (!(rng.uniform() < rules.long_survival)) return WalkEnd::kAbsorbed;
            wt.survived(rules.long_survival);
        }
        if (defer) {
            hooks.at_vertex(s, survive, rng);
            if (!(rng.uniform() < survive)) return WalkEnd::kAbsorbed;
        }
        const double mu = sample_hg(R->g[h], rng.uniform());
        const double phi = 2.0 * kPi * rng.uniform();
        hooks.scattered(s, mu);
        wt.phase(*R, mu);
        s.w = rotate(s.w, mu, phi);
    }
}

/// A smooth dielectric boundary met along w, n its unit normal on the far side (dot(w, n) > 0):
/// exact Fresnel reflectance for the index ratio eta = n_beyond / n_here (total internal
/// reflection included); reflected (true, w mirrored) or transmitted (false, w refracted). One
/// random number. Every engine's smooth boundary, from either side.
inline bool fresnel_reflects(Vec3& w, const Vec3& n, double eta, RngStream& rng) {
    const double cos_i = std::clamp(dot(w, n), 0.0, 1.0);
    double cos_t = 0;
    const double F = fresnel_dielectric(cos_i, eta, cos_t);
    if (rng.uniform() < F) {
        w = normalize(w - n * (2.0 * cos_i));
        return true;
    }
    w = refract(w, -n, eta, cos_t);
    return false;
}

}  // namespace ssslab::volpath
