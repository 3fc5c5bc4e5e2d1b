#include "volpath/mesh_medium.h"

#include "volpath/sampling.h"

#include <cmath>
#include <limits>

namespace ssslab::volpath {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::int64_t kMaxBoundaryHits = 1'000'000;
}  // namespace

template <int NC>
WalkResult walk_mesh_medium(const MeshMedium& m, Vec3 p, Vec3 w, RngStream& rng, int hero) {
    static_assert(NC == 1 || NC == 3);
    constexpr bool kHero = NC == 3;
    const std::size_t h = kHero ? static_cast<std::size_t>(hero) : 0;
    WalkResult r;
    // beta: the channels' weights; q: their strategies' densities over the mixture's, both
    // rescaled after every event (see volpath/pencil.cpp).
    double beta[NC], q[NC];
    for (int c = 0; c < NC; ++c) beta[c] = q[c] = 1.0;
    auto finish = [&](WalkResult::Fate fate) {
        r.fate = fate;
        for (int c = 0; c < NC; ++c) r.weight[static_cast<std::size_t>(c)] = beta[c];
        return r;
    };
    // Flights are sampled at the majorant rate sigma_t max(d) (= sigma_t when homogeneous);
    // a tentative collision is real with probability d(x) / max(d), the same for every channel.
    const double dmax = m.density ? m.density->max_density() : 1.0;
    const double st = m.sigma_t[h] * dmax;
    const double albedo = m.sigma_t[h] > 0 ? m.sigma_s[h] / m.sigma_t[h] : 0.0;
    const double eps = m.scene->epsilon();
    const double eta = m.eta_outside / m.eta_inside;
    auto rescale = [&] {
        if constexpr (kHero) {
            const double s = m.hero_prob[0] * q[0] + m.hero_prob[1] * q[1] + m.hero_prob[2] * q[2];
            for (int c = 0; c < 3; ++c) {
                q[c] /= s;
                beta[c] /= s;
            }
        }
    };
    // A flight of length d ended at an interaction the hero survived (scatter) or at an exit.
    auto flight = [&](double d, bool scatter) {
        if constexpr (kHero) {
            for (int c = 0; c < 3; ++c) {
                const std::size_t i = static_cast<std::size_t>(c);
                const double e = i == h ? 1.0 : std::exp(-(m.sigma_t[i] * dmax - st) * d);
                const double f = scatter ? m.sigma_s[i] / m.sigma_s[h] * e : e;
                q[c] *= f;
                beta[c] *= f;
            }
            rescale();
        }
    };

    bool on_boundary = true;
    for (;;) {
        double t = st > 0 ? -std::log(rng.uniform()) / st : kInf;
        double travelled = 0;
        for (std::int64_t hits = 0;; ++hits) {
            if (hits > kMaxBoundaryHits) return finish(WalkResult::Fate::kLost);
            const RayHit hit = m.scene->intersect(p, w, on_boundary ? eps : 0.0);
            if (!hit.hit() || hit.shape != m.shape) return finish(WalkResult::Fate::kLost);
            if (t < hit.t) {
                p += w * t;
                travelled += t;
                on_boundary = false;
                if (m.density && !(rng.uniform() * dmax < m.density->density(p))) {
                    // A null collision: the path goes on in the same direction. Hero mode: the
                    // channels' densities of this tentative collision differ by their
                    // majorants (the null probability is the same for all).
                    if constexpr (kHero) {
                        for (int c = 0; c < 3; ++c) {
                            const std::size_t i = static_cast<std::size_t>(c);
                            const double sm = m.sigma_t[i] * dmax;
                            const double f =
                                i == h ? 1.0 : sm / st * std::exp(-(sm - st) * travelled);
                            q[c] *= f;
                            beta[c] *= f;
                        }
                        rescale();
                    }
                    travelled = 0;
                    t = -std::log(rng.uniform()) / st;
                    continue;
                }
                break;
            }
            p += w * hit.t;
            travelled += hit.t;
            on_boundary = true;
            const double cos_i = dot(w, hit.normal);  // leaving: along the outward normal
            if (!(cos_i > 0)) {
                // Met from outside within a few epsilons: the restart point slipped across a
                // concave crease; the path is inside, so it crosses back and goes on.
                if (hit.t < 4 * eps && !(cos_i != cos_i)) {
                    t -= hit.t;
                    continue;
                }
                return finish(WalkResult::Fate::kLost);
            }
            double cos_t = 0;
            const double F = fresnel_dielectric(cos_i, eta, cos_t);
            if (rng.uniform() < F) {  // internal reflection; the free path goes on
                w = reflect(w, hit.normal);
                t -= hit.t;
                // Restart just inside the face: from the surface itself a ray can slip through
                // a concave crease (single-precision hits) and meet the next face from outside.
                p += hit.normal * -eps;
                on_boundary = false;
                continue;
            }
            flight(travelled, false);
            r.p = p;
            r.n = hit.normal;
            r.w = refract(w, -hit.normal, eta, cos_t);
            return finish(WalkResult::Fate::kExited);
        }
        ++r.events;
        if (!(rng.uniform() < albedo)) return finish(WalkResult::Fate::kAbsorbed);
        flight(travelled, true);
        if (r.events > m.long_events) {
            if (!(rng.uniform() < m.long_survival)) return finish(WalkResult::Fate::kAbsorbed);
            for (int c = 0; c < NC; ++c) beta[c] /= m.long_survival;
        }
        const double g = m.g[h];
        const double mu = sample_hg(g, rng.uniform());
        const double phi = 2.0 * kPi * rng.uniform();
        if constexpr (kHero) {
            if (!(m.g[0] == m.g[1] && m.g[1] == m.g[2])) {
                const double ph = hg_pdf(g, mu);
                for (int c = 0; c < 3; ++c) {
                    const double f = hg_pdf(m.g[static_cast<std::size_t>(c)], mu) / ph;
                    q[c] *= f;
                    beta[c] *= f;
                }
                rescale();
            }
        }
        w = rotate(w, mu, phi);
    }
}

template WalkResult walk_mesh_medium<1>(const MeshMedium&, Vec3, Vec3, RngStream&, int);
template WalkResult walk_mesh_medium<3>(const MeshMedium&, Vec3, Vec3, RngStream&, int);

}  // namespace ssslab::volpath
