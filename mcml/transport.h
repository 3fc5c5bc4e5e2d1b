// Photon transport of MCML 1.2.2: hop, drop, spin, with Fresnel decisions at every interface and
// weight roulette [Wang, Jacques & Zheng 1995; MCML manual ch. 3-4].
//
// One template serves both modes:
//  - kCompat = true reproduces the original program operation for operation: its random number
//    call order, PI = 3.1415926, the azimuth from cos() and a square root, the HG formula of
//    SpinTheta(), divisions where it divides. Fed with the original's ran3 stream, it makes the
//    same decisions and deposits the same weights, so its .mco is byte-identical.
//  - kCompat = false is the default engine: same physics and same estimator, with exact pi,
//    sincos() for the azimuth, a cancellation-free HG inversion for small |g| (g < 0 allowed), and
//    per-layer constants precomputed. Its random numbers come from counter-based streams.
// The sink receives deposited weights (absorption, reflection, transmission); see tally_sinks.h.
#pragma once

#include "core/fastmath.h"
#include "core/ziggurat.h"
#include "mcml/run_spec.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace ssslab::mcml {

inline constexpr double kMcmlPi = 3.1415926;  ///< MCML 1.2.2's PI (mcml.h)
inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kCosZero = 1.0 - 1.0e-12;  ///< cosine of about 1e-6 rad
inline constexpr double kCos90D = 1.0e-6;          ///< cosine of about 1.57 - 1e-6 rad
inline constexpr double kWeightThreshold = 1e-4;   ///< roulette threshold (WEIGHT)
inline constexpr double kRouletteChance = 0.1;     ///< roulette survival (CHANCE)

/// Henyey-Greenstein deflection cosine from a uniform u, as MCML's SpinTheta(): the inverse CDF
/// cos = (1 + g^2 - ((1 - g^2) / (1 - g + 2 g u))^2) / (2 g), and 2u - 1 for g = 0.
inline double sample_hg_cos_mcml(double g, double u) {
    double cost;
    if (std::fabs(g) == 1.0) {
        // The formula is 0/0 for g = 1, u = 0 and g = -1, u = 1, and ran3 can return 0 and 1:
        // the original then turns NaN into an array index (undefined behaviour). The limit is
        // returned instead; for every other draw it is what the formula gives.
        return g;
    }
    if (g == 0.0) {
        cost = 2 * u - 1;
    } else {
        const double temp = (1 - g * g) / (1 - g + 2 * g * u);
        cost = (1 + g * g - temp * temp) / (2 * g);
        if (cost < -1)
            cost = -1;
        else if (cost > 1)
            cost = 1;
    }
    return cost;
}

/// The same inverse CDF, free of cancellation for small |g|. With s = 2u - 1 the MCML formula
/// expands to  cos = (s + g (3 + s^2) / 2 + g^2 s + g^3 (s^2 - 1) / 2) / (1 + g s)^2,  whose
/// rounding error is O(eps / (1 - |g|)^2): used for |g| <= 1/2. For |g| > 1/2 the MCML form is
/// accurate (its error is O(eps / |g|)). Valid for g in [-1, 1]; u in (0, 1).
inline double sample_hg_cos(double g, double u) {
    double cost;
    if (std::fabs(g) <= 0.5) {
        const double s = 2.0 * u - 1.0;
        const double d = 1.0 + g * s;
        cost = (s + g * (0.5 * (3.0 + s * s) + g * (s + g * 0.5 * (s * s - 1.0)))) / (d * d);
    } else {
        const double temp = (1 - g * g) / (1 - g + 2 * g * u);
        cost = (1 + g * g - temp * temp) / (2 * g);
    }
    return cost < -1.0 ? -1.0 : (cost > 1.0 ? 1.0 : cost);
}

/// Fresnel reflectance for unpolarised light, MCML's RFresnel(): n1 incident, n2 transmitted, ca1
/// the incident cosine (0..1, below the critical angle); writes the transmitted cosine to *ca2.
inline double fresnel_mcml(double n1, double n2, double ca1, double* ca2_ptr) {
    double r;
    if (n1 == n2) {
        *ca2_ptr = ca1;
        r = 0.0;
    } else if (ca1 > kCosZero) {
        *ca2_ptr = ca1;
        r = (n2 - n1) / (n2 + n1);
        r *= r;
    } else if (ca1 < kCos90D) {
        *ca2_ptr = 0.0;
        r = 1.0;
    } else {
        double sa1, sa2, ca2;
        sa1 = std::sqrt(1 - ca1 * ca1);
        sa2 = n1 * sa1 / n2;
        if (sa2 >= 1.0) {
            *ca2_ptr = 0.0;
            r = 1.0;
        } else {
            double cap, cam, sap, sam;
            *ca2_ptr = ca2 = std::sqrt(1 - sa2 * sa2);
            cap = ca1 * ca2 - sa1 * sa2;
            cam = ca1 * ca2 + sa1 * sa2;
            sap = sa1 * ca2 + ca1 * sa2;
            sam = sa1 * ca2 - ca1 * sa2;
            r = 0.5 * sam * sam * (cam * cam + cap * cap) / (sap * sap * cam * cam);
        }
    }
    return r;
}

/// New direction after a scattering event with HG anisotropy g (MCML's Spin()): deflection
/// cosine from the HG inverse CDF, azimuth uniform in [0, 2 pi), rotated into the frame of the old
/// direction (ux, uy, uz), which is overwritten. Draws two uniforms from rng, in the original's
/// order (theta, then psi). In compatibility mode every operation is the original's; in default
/// mode isotropic scattering (g = 0) draws the new direction directly, since it does not depend
/// on the old one, and the azimuth comes from sincos_2pi().
template <bool kCompat, class Rng>
[[gnu::always_inline]] inline void spin_direction(double g, double& ux_io, double& uy_io,
                                                  double& uz_io, Rng& rng) {
    double cost, sint, cosp, sinp;
    const double ux = ux_io, uy = uy_io, uz = uz_io;
    if constexpr (kCompat) {
        cost = sample_hg_cos_mcml(g, rng.uniform());
        sint = std::sqrt(1.0 - cost * cost);
        const double psi = 2.0 * kMcmlPi * rng.uniform();
        cosp = std::cos(psi);
        if (psi < kMcmlPi)
            sinp = std::sqrt(1.0 - cosp * cosp);
        else
            sinp = -std::sqrt(1.0 - cosp * cosp);
    } else {
        if (g == 0.0) {
            uz_io = 2.0 * rng.uniform() - 1.0;
            sint = std::sqrt(1.0 - uz_io * uz_io);
            sincos_2pi(rng.uniform(), &sinp, &cosp);
            ux_io = sint * cosp;
            uy_io = sint * sinp;
            return;
        }
        cost = sample_hg_cos(g, rng.uniform());
        sint = std::sqrt(1.0 - cost * cost);
        sincos_2pi(rng.uniform(), &sinp, &cosp);
    }
    if (std::fabs(uz) > kCosZero) {  // normal incidence
        ux_io = sint * cosp;
        uy_io = sint * sinp;
        uz_io = cost * (uz >= 0 ? 1 : -1);
    } else if constexpr (kCompat) {
        const double temp = std::sqrt(1.0 - uz * uz);
        ux_io = sint * (ux * uz * cosp - uy * sinp) / temp + ux * cost;
        uy_io = sint * (uy * uz * cosp + ux * sinp) / temp + uy * cost;
        uz_io = -sint * cosp * temp + uz * cost;
    } else {
        // sqrt(ux^2 + uy^2) rather than MCML's sqrt(1 - uz^2): near the z axis 1 - uz^2 has lost
        // most of its digits (at |uz| = 1 - 1e-12 the new direction's length was off by 1e-4).
        const double temp = std::sqrt(ux * ux + uy * uy);
        const double f = sint / temp;
        ux_io = f * (ux * uz * cosp - uy * sinp) + ux * cost;
        uy_io = f * (uy * uz * cosp + ux * sinp) + uy * cost;
        uz_io = -sint * cosp * temp + uz * cost;
    }
}

/// A photon packet (MCML's PhotonStruct).
struct Photon {
    double x = 0, y = 0, z = 0;     ///< position [cm]
    double ux = 0, uy = 0, uz = 1;  ///< direction cosines
    double w = 1;                   ///< weight
    double s = 0;                   ///< current step [cm]
    double sleft = 0;               ///< step left over after a boundary, in mean free paths
    int layer = 1;
    bool dead = false;
};

/// Per-layer constants for the default engine.
struct LayerConst {
    double mut = 0, inv_mut = 0, absorb = 0;  // mua + mus, its inverse, mua / (mua + mus)
};

template <bool kCompat, class Rng, class Sink>
class Transport {
  public:
    Transport(const RunSpec& run, Rng& rng, Sink& sink)
        : L_(run.layers), num_layers_(run.num_layers()), rng_(rng), sink_(sink) {
        consts_.resize(L_.size());
        for (size_t i = 0; i < L_.size(); ++i) {
            const double mut = L_[i].mua + L_[i].mus;
            consts_[i].mut = mut;
            consts_[i].inv_mut = mut > 0 ? 1.0 / mut : 0.0;
            consts_[i].absorb = mut > 0 ? L_[i].mua / mut : 0.0;
        }
    }

    /// Trace one photon packet from launch to death (DoOneRun's inner loop).
    void trace(double rsp) {
        Photon p;
        launch(rsp, p);
        do hop_drop_spin(p);
        while (!p.dead);
    }

    /// Trace `n` photons, `kLanes` at a time in interleaved order: the photons of different
    /// lanes are independent, so their long dependency chains (log, sqrt, division) overlap in the
    /// out-of-order core. A dead lane takes the next photon. The draw order from the stream is a
    /// fixed function of the stream itself, so the result is deterministic. Default mode only:
    /// compatibility mode traces photons one after the other, as the original.
    void trace_interleaved(std::int64_t n, double rsp) {
        static_assert(!kCompat, "compatibility mode traces photons in the original order");
        constexpr int kLanes = 2;
        Photon p[kLanes];
        std::int64_t launched = 0;
        int active = 0;
        for (auto& q : p) {
            if (launched < n) {
                launch(rsp, q);
                ++launched;
                ++active;
            } else {
                q.dead = true;
            }
        }
        while (active > 0) {
            for (auto& q : p) {
                if (q.dead) continue;
                hop_drop_spin(q);
                if (q.dead) {
                    if (launched < n) {
                        launch(rsp, q);
                        ++launched;
                    } else {
                        --active;
                    }
                }
            }
        }
    }

    std::uint64_t events() const { return events_; }

  private:
    double rnd() { return rng_.uniform(); }

    void launch(double rsp, Photon& p) const {
        p = Photon{};
        p.w = 1.0 - rsp;
        p.layer = 1;
        if (L_[1].glass()) {
            p.layer = 2;
            p.z = L_[2].z0;
        }
    }

    void spin(double g, Photon& p) {
        ++events_;
        spin_direction<kCompat>(g, p.ux, p.uy, p.uz, rng_);
    }

    static void hop(Photon& p) {
        const double s = p.s;
        p.x += s * p.ux;
        p.y += s * p.uy;
        p.z += s * p.uz;
    }

    void step_size_in_tissue(Photon& p) {
        const Layer& l = L_[static_cast<size_t>(p.layer)];
        if (p.sleft == 0.0) {
            if constexpr (kCompat) {
                double r;
                do r = rnd();
                while (r <= 0.0);
                p.s = -std::log(r) / (l.mua + l.mus);
            } else {
                p.s = ExpZiggurat::sample(rng_) * consts_[static_cast<size_t>(p.layer)].inv_mut;
            }
        } else {
            if constexpr (kCompat)
                p.s = p.sleft / (l.mua + l.mus);
            else
                p.s = p.sleft * consts_[static_cast<size_t>(p.layer)].inv_mut;
            p.sleft = 0.0;
        }
    }

    bool hit_boundary(Photon& p) const {
        const Layer& l = L_[static_cast<size_t>(p.layer)];
        const double uz = p.uz;
        if constexpr (kCompat) {
            double dl_b = 0.0;
            if (uz > 0.0)
                dl_b = (l.z1 - p.z) / uz;
            else if (uz < 0.0)
                dl_b = (l.z0 - p.z) / uz;
            if (uz != 0.0 && p.s > dl_b) {
                const double mut = l.mua + l.mus;
                p.sleft = (p.s - dl_b) * mut;
                p.s = dl_b;
                return true;
            }
            return false;
        } else {
            // s > (zb - z) / uz without the division on the common path where the step ends
            // inside the layer.
            // Moving up or down, the step crosses iff |s uz| > |zb - z| (never when uz = 0).
            const double zb = uz > 0.0 ? l.z1 : l.z0;
            if (std::fabs(p.s * uz) > std::fabs(zb - p.z)) {
                const double dl_b = (zb - p.z) / uz;
                p.sleft = (p.s - dl_b) * consts_[static_cast<size_t>(p.layer)].mut;
                p.s = dl_b;
                return true;
            }
            return false;
        }
    }

    void drop(Photon& p) {
        const Layer& l = L_[static_cast<size_t>(p.layer)];
        double dwa;
        if constexpr (kCompat)
            dwa = p.w * l.mua / (l.mua + l.mus);
        else
            dwa = p.w * consts_[static_cast<size_t>(p.layer)].absorb;
        p.w -= dwa;
        sink_.absorb(p, dwa);
    }

    void roulette(Photon& p) {
        if (p.w == 0.0)
            p.dead = true;
        else if (rnd() < kRouletteChance)
            p.w /= kRouletteChance;
        else
            p.dead = true;
    }

    void cross_up_or_not(Photon& p) {
        const double uz = p.uz;
        double uz1 = 0.0, r;
        const int layer = p.layer;
        const double ni = L_[static_cast<size_t>(layer)].n;
        const double nt = L_[static_cast<size_t>(layer - 1)].n;
        if (-uz <= L_[static_cast<size_t>(layer)].cos_crit0)
            r = 1.0;
        else
            r = fresnel_mcml(ni, nt, -uz, &uz1);
        if (rnd() > r) {
            if (layer == 1) {
                p.uz = -uz1;
                sink_.reflect(p);
                p.w = 0.0;
                p.dead = true;
            } else {
                p.layer--;
                p.ux *= ni / nt;
                p.uy *= ni / nt;
                p.uz = -uz1;
            }
        } else {
            p.uz = -uz;
        }
    }

    void cross_dn_or_not(Photon& p) {
        const double uz = p.uz;
        double uz1 = 0.0, r;
        const int layer = p.layer;
        const double ni = L_[static_cast<size_t>(layer)].n;
        const double nt = L_[static_cast<size_t>(layer + 1)].n;
        if (uz <= L_[static_cast<size_t>(layer)].cos_crit1)
            r = 1.0;
        else
            r = fresnel_mcml(ni, nt, uz, &uz1);
        if (rnd() > r) {
            if (layer == num_layers_) {
                p.uz = uz1;
                sink_.transmit(p);
                p.w = 0.0;
                p.dead = true;
            } else {
                p.layer++;
                p.ux *= ni / nt;
                p.uy *= ni / nt;
                p.uz = uz1;
            }
        } else {
            p.uz = -uz;
        }
    }

    void cross_or_not(Photon& p) {
        if (p.uz < 0.0)
            cross_up_or_not(p);
        else
            cross_dn_or_not(p);
    }

    void hop_in_glass(Photon& p) {
        if (p.uz == 0.0) {
            p.dead = true;  // a horizontal photon in glass never reaches tissue again
        } else {
            const Layer& l = L_[static_cast<size_t>(p.layer)];
            double dl_b = 0.0;
            if (p.uz > 0.0)
                dl_b = (l.z1 - p.z) / p.uz;
            else if (p.uz < 0.0)
                dl_b = (l.z0 - p.z) / p.uz;
            p.s = dl_b;
            hop(p);
            cross_or_not(p);
        }
    }

    void hop_drop_spin_in_tissue(Photon& p) {
        step_size_in_tissue(p);
        if (hit_boundary(p)) {
            hop(p);
            cross_or_not(p);
        } else {
            hop(p);
            drop(p);
            spin(L_[static_cast<size_t>(p.layer)].g, p);
        }
    }

    void hop_drop_spin(Photon& p) {
        if (L_[static_cast<size_t>(p.layer)].glass())
            hop_in_glass(p);
        else
            hop_drop_spin_in_tissue(p);
        if (p.w < kWeightThreshold && !p.dead) roulette(p);
    }

    const std::vector<Layer>& L_;
    const int num_layers_;
    std::vector<LayerConst> consts_;
    Rng& rng_;
    Sink& sink_;
    std::uint64_t events_ = 0;
};

}  // namespace ssslab::mcml
