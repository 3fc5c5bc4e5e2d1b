// A radial profile integrated over the lit sphere [Bitterli13 §3.5]; see sphere_bssrdf.h.
#include "approx/sphere_bssrdf.h"

#include "approx/diffusion.h"
#include "core/format.h"
#include "core/quadrature.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>

namespace ssslab::approx {

namespace {

constexpr double kPi = 3.14159265358979323846;

// ---- Gauss-Kronrod 7/15 (QUADPACK qk15) -------------------------------------------------------

constexpr std::array<double, 8> kXgk = {
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.0};
constexpr std::array<double, 8> kWgk = {
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
constexpr std::array<double, 4> kWg = {
    0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
    0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

struct Panel {
    int part = 0;
    double a = 0, b = 0, value = 0, error = 0;
    bool operator<(const Panel& o) const { return error < o.error; }
};

template <class F>
Panel gk15(F& f, int part, double a, double b) {
    const double c = 0.5 * (a + b), h = 0.5 * (b - a);
    const double fc = f(part, c);
    double k = fc * kWgk[7], g = fc * kWg[3];
    for (size_t j = 0; j < 7; ++j) {
        const double x = h * kXgk[j];
        const double s = f(part, c - x) + f(part, c + x);
        k += kWgk[j] * s;
        if (j % 2 == 1) g += kWg[j / 2] * s;
    }
    return {part, a, b, k * h, std::abs((k - g) * h)};
}

// Globally adaptive Gauss-Kronrod over the initial panels (part, a, b): the panel with the
// largest error estimate is halved until the summed estimate is at most
// max(abs_tol, rel_tol |I|) or max_panels panels exist. f(part, x).
template <class F>
double adaptive(F&& f, const std::vector<Panel>& initial, double rel_tol, double abs_tol,
                int max_panels, double& error) {
    std::priority_queue<Panel> heap;
    double value = 0;
    error = 0;
    for (const Panel& p0 : initial) {
        if (!(p0.b > p0.a)) continue;
        const Panel p = gk15(f, p0.part, p0.a, p0.b);
        value += p.value;
        error += p.error;
        heap.push(p);
    }
    int panels = static_cast<int>(heap.size());
    while (!heap.empty() && error > std::max(abs_tol, rel_tol * std::abs(value)) &&
           panels < max_panels) {
        const Panel p = heap.top();
        const double m = 0.5 * (p.a + p.b);
        if (!(m > p.a && m < p.b)) break;  // cannot be split further in double precision
        heap.pop();
        const Panel l = gk15(f, p.part, p.a, m), r = gk15(f, p.part, m, p.b);
        value += l.value + r.value - p.value;
        error += l.error + r.error - p.error;
        heap.push(l);
        heap.push(r);
        ++panels;
    }
    // Re-sum to shed the rounding of the running updates.
    value = 0;
    error = 0;
    while (!heap.empty()) {
        value += heap.top().value;
        error += heap.top().error;
        heap.pop();
    }
    return value;
}

// ---- The entry weight -------------------------------------------------------------------------

struct Entry {
    EntryWeight kind = EntryWeight::kFresnel;
    double eta = 1;
    double scale = 1;  // 1 / (1 - F(1)) for profiles that carry the normal-incidence factor
    double cut = 0;    // E_t = 0 for mu <= cut (the critical angle for eta < 1)

    explicit Entry(const SphereIntegration& o) : kind(o.entry), eta(o.eta) {
        if (kind == EntryWeight::kFresnel) {
            if (o.profile_entry_fresnel) scale = 1.0 / (1.0 - dielectric_reflectance(1.0, eta));
            if (eta < 1) cut = std::sqrt((1 - eta) * (1 + eta));
        }
    }
    double operator()(double mu) const {
        if (!(mu > cut)) return 0.0;
        mu = std::min(mu, 1.0);
        if (kind == EntryWeight::kCosineOnly) return mu;
        return mu * (1.0 - dielectric_reflectance(mu, eta)) * scale;
    }
};

// G(psi, beta) = (1 / 2 pi) int_0^2pi E_t(a + b cos phi) dphi, a = cos psi cos beta,
// b = sin psi sin beta >= 0 (see the header).
double azimuthal_average(const Entry& e, double a, double b) {
    if (!(b > 1e-300)) return e(a);
    const double hi = a + b, lo = a - b;
    if (hi <= e.cut) return 0.0;
    if (e.kind == EntryWeight::kCosineOnly) {
        if (lo >= 0) return a;
        // phi0 = acos(-a / b): a phi0 + b sin phi0, sin phi0 = sqrt((b - a)(b + a)) / b.
        const double phi0 = std::acos(std::clamp(-a / b, -1.0, 1.0));
        const double s = std::sqrt(std::max(0.0, (b - a) * (b + a)));
        return std::max(0.0, (a * phi0 + s) / kPi);
    }
    if (lo >= e.cut) {
        // The whole circle is lit: (1 / pi) int_0^pi f(a + b cos phi) dphi is a Gauss-Chebyshev
        // integral of f(a + b x) over x in [-1, 1]; the 18-point rule holds the 6-point one,
        // and for an integrand analytic in x (eta >= 1) its error is about the cube of their
        // difference, so a difference below 1e-5 leaves ~1e-15.
        static const std::array<double, 18> kX = [] {
            std::array<double, 18> x{};
            for (int k = 0; k < 18; ++k)
                x[static_cast<size_t>(k)] = std::cos((2 * k + 1) * kPi / 36);
            return x;
        }();
        double s6 = 0, s18 = 0;
        for (int k = 0; k < 18; ++k) {
            const double v = e(a + b * kX[static_cast<size_t>(k)]);
            s18 += v;
            if (k % 3 == 1) s6 += v;
        }
        s6 /= 6;
        s18 /= 18;
        if (std::abs(s18 - s6) <= 1e-5 * std::abs(s18)) return s18;
    }
    const double phi0 = lo >= e.cut ? kPi : std::acos(std::clamp((e.cut - a) / b, -1.0, 1.0));
    auto f = [&](int, double phi) { return e(a + b * std::cos(phi)); };
    // One panel is usually enough (the integrand is analytic in phi for eta >= 1); the adaptive
    // rule only where it is not.
    const Panel p = gk15(f, 0, 0.0, phi0);
    if (p.error <= std::max(1e-17, 1e-13 * std::abs(p.value))) return p.value / kPi;
    double err = 0;
    return adaptive(f, {Panel{0, 0.0, phi0}}, 1e-13, 1e-17, 200, err) / kPi;
}

// ---- The profile as a piecewise Chebyshev interpolant -----------------------------------------

// The radial weight of the outer integral on its two parts: part 0 in s = ln r on
// [s_min, s_split], w = 2 pi r^2 R_d(r); part 1 in psi on [pi/2, pi], w = 2 pi R^2 sin psi
// R_d(2 R sin(psi / 2)). Each part is a sorted list of panels holding the Chebyshev coefficients
// of w on 17 Chebyshev-Lobatto points.
constexpr int kChebN = 17;
constexpr double kRelMin = 1e-15;  // r_min = kRelMin * 2R

struct ChebPanel {
    double a = 0, b = 0;
    std::array<double, kChebN> c{};
};

class RadialWeight {
  public:
    using Samples = std::array<double, kChebN>;

    RadialWeight(const RadialFunction& rd, double radius, double tol)
        : rd_(rd), radius_(radius), tol_(tol) {
        s_min_ = std::log(2 * radius * kRelMin);
        s_split_ = std::log(std::sqrt(2.0) * radius);
        // The initial panels, sampled first: their largest value sets the floor below which
        // the weight need not be resolved relative to itself.
        struct Initial {
            int part;
            double a, b;
            Samples f;
        };
        std::vector<Initial> init;
        const int nl = static_cast<int>(std::ceil(s_split_ - s_min_));
        for (int i = 0; i < nl; ++i)
            init.push_back({0,
                            s_min_ + (s_split_ - s_min_) * i / nl,
                            i + 1 == nl ? s_split_ : s_min_ + (s_split_ - s_min_) * (i + 1) / nl,
                            {}});
        for (int i = 0; i < 16; ++i)
            init.push_back({1,
                            0.5 * kPi * (1 + i / 16.0),
                            i == 15 ? kPi : 0.5 * kPi * (1 + (i + 1) / 16.0),
                            {}});
        double peak = 0;
        for (Initial& p : init) {
            p.f = sample(p.part, p.a, p.b);
            for (double v : p.f) peak = std::max(peak, std::abs(v));
        }
        floor_ = kFloor * peak;
        for (const Initial& p : init) refine(p.part, p.a, p.b, p.f, 0);
    }

    double s_min() const { return s_min_; }
    double s_split() const { return s_split_; }
    std::uint64_t evaluations() const { return evaluations_; }
    double fit_error() const { return fit_error_; }

    double operator()(int part, double x) const {
        const std::vector<ChebPanel>& P = panels_[static_cast<size_t>(part)];
        auto it = std::upper_bound(P.begin(), P.end(), x,
                                   [](double v, const ChebPanel& p) { return v < p.a; });
        const ChebPanel& p = it == P.begin() ? P.front() : *(it - 1);
        // Clenshaw.
        const double t = std::clamp((2 * x - p.a - p.b) / (p.b - p.a), -1.0, 1.0);
        double b1 = 0, b2 = 0;
        for (int k = kChebN - 1; k >= 1; --k) {
            const double b0 = 2 * t * b1 - b2 + p.c[static_cast<size_t>(k)];
            b2 = b1;
            b1 = b0;
        }
        return t * b1 - b2 + p.c[0];
    }

  private:
    double weight(int part, double x) {
        ++evaluations_;
        double r, jac;
        if (part == 0) {
            r = std::exp(x);
            jac = r * r;
        } else {
            r = 2 * radius_ * std::sin(0.5 * x);
            jac = radius_ * radius_ * std::sin(x);
        }
        const double v = rd_(r);
        if (!std::isfinite(v))
            throw std::invalid_argument("sphere integration: the profile is not finite at r = " +
                                        format_g(r, 17));
        return 2 * kPi * jac * v;
    }

    // The weight at the Chebyshev-Lobatto points of [a, b], from b down to a.
    Samples sample(int part, double a, double b) {
        Samples f{};
        for (int j = 0; j < kChebN; ++j)
            f[static_cast<size_t>(j)] =
                weight(part, 0.5 * (a + b) + 0.5 * (b - a) * std::cos(kPi * j / (kChebN - 1)));
        return f;
    }

    void refine(int part, double a, double b, const Samples& f, int depth) {
        constexpr int n = kChebN - 1;
        double fmax = 0;
        for (double v : f) fmax = std::max(fmax, std::abs(v));
        ChebPanel p;
        p.a = a;
        p.b = b;
        for (int k = 0; k <= n; ++k) {
            double s = 0;
            for (int j = 0; j <= n; ++j)
                s += f[static_cast<size_t>(j)] * ((j == 0 || j == n) ? 0.5 : 1.0) *
                     std::cos(kPi * j * k / n);
            s *= 2.0 / n;
            if (k == 0 || k == n) s *= 0.5;
            p.c[static_cast<size_t>(k)] = s;
        }
        const double tail =
            std::max({std::abs(p.c[n]), std::abs(p.c[n - 1]), std::abs(p.c[n - 2])});
        const double scale = std::max(fmax, floor_);
        if (tail > tol_ * scale && depth < 40 && b - a > 1e-7 && total_panels_ < kMaxPanels) {
            ++total_panels_;
            const double m = 0.5 * (a + b);
            const Samples fl = sample(part, a, m), fr = sample(part, m, b);
            refine(part, a, m, fl, depth + 1);
            refine(part, m, b, fr, depth + 1);
            return;
        }
        if (scale > 0) fit_error_ = std::max(fit_error_, tail / scale);
        panels_[static_cast<size_t>(part)].push_back(p);
    }

    static constexpr int kMaxPanels = 20000;
    // Below kFloor times the weight's peak, a panel is resolved to tol relative to that floor.
    static constexpr double kFloor = 1e-30;
    const RadialFunction& rd_;
    double radius_, tol_;
    double s_min_ = 0, s_split_ = 0, floor_ = 0;
    std::array<std::vector<ChebPanel>, 2> panels_;
    std::uint64_t evaluations_ = 0;
    int total_panels_ = 0;
    double fit_error_ = 0;
};

// M(beta) for a built weight; `evals` counts integrand evaluations.
double exitance_at(const RadialWeight& w, const Entry& e, const SphereIntegration& o, double beta,
                   double& error, std::uint64_t& evals) {
    const double R = o.radius;
    const double cb = std::cos(beta), sb = std::sin(beta);
    auto integrand = [&](int part, double x) {
        ++evals;
        double cpsi, spsi;
        if (part == 0) {
            const double h = std::exp(x) / (2 * R);
            cpsi = 1 - 2 * h * h;
            spsi = 2 * h * std::sqrt(std::max(0.0, 1 - h * h));
        } else {
            cpsi = std::cos(x);
            spsi = std::sin(x);
        }
        const double g = azimuthal_average(e, cpsi * cb, spsi * sb);
        return g == 0 ? 0.0 : w(part, x) * g;
    };
    // Breakpoints: panels of width <= 2 in s (a profile's r^2 R_d spans at least ~1 in ln r, so
    // the 15 points of a panel cannot miss it) and pi/16 in psi, and the kinks of G where the
    // circle psi = const touches the level mu = cut (|psi - beta| = theta0 or psi + beta =
    // theta0, 2 pi - theta0).
    std::vector<double> bl, bp;
    const double s0 = w.s_min(), s1 = w.s_split();
    const int nl = static_cast<int>(std::ceil(0.5 * (s1 - s0)));
    for (int i = 0; i <= nl; ++i) bl.push_back(i == nl ? s1 : s0 + (s1 - s0) * i / nl);
    for (int i = 0; i <= 8; ++i) bp.push_back(i == 8 ? kPi : 0.5 * kPi * (1 + i / 8.0));
    const double theta0 = std::acos(e.cut);
    for (double psi : {beta - theta0, beta + theta0, theta0 - beta, 2 * kPi - theta0 - beta}) {
        if (!(psi > 0 && psi < kPi)) continue;
        if (psi < 0.5 * kPi) {
            const double s = std::log(2 * R * std::sin(0.5 * psi));
            if (s > s0 && s < s1) bl.push_back(s);
        } else if (psi > 0.5 * kPi) {
            bp.push_back(psi);
        }
    }
    std::sort(bl.begin(), bl.end());
    std::sort(bp.begin(), bp.end());
    std::vector<Panel> initial;
    for (size_t i = 0; i + 1 < bl.size(); ++i) initial.push_back({0, bl[i], bl[i + 1], 0, 0});
    for (size_t i = 0; i + 1 < bp.size(); ++i) initial.push_back({1, bp[i], bp[i + 1], 0, 0});
    return adaptive(integrand, initial, o.rel_tol, 0.0, o.max_panels, error);
}

template <class F>
void in_arena(int threads, F&& f) {
    if (threads > 0) {
        tbb::task_arena arena(threads);
        arena.execute(f);
    } else {
        f();
    }
}

std::array<double, 3> unit(const std::array<double, 3>& a, const char* what) {
    const double len = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (!std::isfinite(a[0]) || !std::isfinite(a[1]) || !std::isfinite(a[2]) || !(len > 1e-300) ||
        !std::isfinite(len))
        throw std::invalid_argument(std::string("sphere view: ") + what +
                                    " must be a finite non-zero vector");
    return {a[0] / len, a[1] / len, a[2] / len};
}

double dot(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

}  // namespace

const char* to_string(EntryWeight w) {
    return name_of(w).data();
}

double dielectric_reflectance(double mu, double eta) {
    if (eta == 1.0) return 0.0;
    mu = std::clamp(mu, 0.0, 1.0);
    // Snell: sin_t = sin_i / eta.
    const double sin2_t = (1.0 - mu * mu) / (eta * eta);
    if (sin2_t >= 1.0) return 1.0;
    const double ct = std::sqrt(1.0 - sin2_t);
    const double rs = (mu - eta * ct) / (mu + eta * ct);
    const double rp = (eta * mu - ct) / (eta * mu + ct);
    return 0.5 * (rs * rs + rp * rp);
}

void validate(const SphereIntegration& o) {
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("sphere integration: " + what);
    };
    if (!(o.radius > 0) || !std::isfinite(o.radius)) fail("radius must be finite and > 0");
    if (!(o.eta > 0) || !std::isfinite(o.eta)) fail("eta must be finite and > 0");
    if (o.beta_bins < 1 || o.beta_bins > 1'000'000) fail("beta_bins must lie in [1, 1e6]");
    if (o.nodes_per_bin < 1 || o.nodes_per_bin > 16) fail("nodes_per_bin must lie in [1, 16]");
    if (!(o.rel_tol >= 1e-15 && o.rel_tol <= 1e-2)) fail("rel_tol must lie in [1e-15, 1e-2]");
    if (o.max_panels < 16) fail("max_panels must be >= 16");
    if (o.threads < 0) fail("threads must be >= 0");
}

double transmitted_irradiance(double mu, const SphereIntegration& o) {
    return Entry(o)(mu);
}

double sphere_exitance_at(const RadialFunction& rd, double beta, const SphereIntegration& o,
                          double* error) {
    validate(o);
    if (!(beta >= 0 && beta <= kPi))
        throw std::invalid_argument("sphere integration: beta must lie in [0, pi]");
    const RadialWeight w(rd, o.radius, 0.1 * o.rel_tol);
    std::uint64_t evals = 0;
    double err = 0;
    const double v = exitance_at(w, Entry(o), o, beta, err, evals);
    if (error) *error = err;
    return v;
}

double SphereExitance::beta_edge(int j) const {
    return j >= options.beta_bins ? kPi : kPi * j / options.beta_bins;
}

double SphereExitance::at(double beta) const {
    const std::vector<double>& x = node_beta;
    const std::vector<double>& y = node_value;
    if (x.empty()) return 0.0;
    beta = std::clamp(beta, x.front(), x.back());
    size_t i = static_cast<size_t>(std::upper_bound(x.begin(), x.end(), beta) - x.begin());
    i = std::clamp<size_t>(i, 1, x.size() - 1) - 1;
    const double h = x[i + 1] - x[i];
    const double t = (beta - x[i]) / h;
    const double t2 = t * t, t3 = t2 * t;
    return (2 * t3 - 3 * t2 + 1) * y[i] + (t3 - 2 * t2 + t) * h * node_slope[i] +
           (-2 * t3 + 3 * t2) * y[i + 1] + (t3 - t2) * h * node_slope[i + 1];
}

double SphereExitance::total_fraction() const {
    double sum = 0;
    for (int j = 0; j < static_cast<int>(bin_mean.size()); ++j)
        sum += 2.0 * bin_mean[static_cast<size_t>(j)] *
               (std::cos(beta_edge(j)) - std::cos(beta_edge(j + 1)));
    return sum;
}

SphereExitance integrate_sphere(const RadialFunction& rd, const SphereIntegration& o) {
    validate(o);
    const auto start = std::chrono::steady_clock::now();
    SphereExitance out;
    out.options = o;
    const RadialWeight w(rd, o.radius, 0.1 * o.rel_tol);
    const Entry e(o);

    // Nodes: per bin the Gauss-Legendre nodes in u = cos beta, by increasing beta; both poles.
    std::vector<double> gx, gw;
    gauss_legendre(o.nodes_per_bin, gx, gw);
    const int nb = o.beta_bins, nn = o.nodes_per_bin;
    out.node_beta.push_back(0.0);
    for (int j = 0; j < nb; ++j) {
        const double u0 = std::cos(out.beta_edge(j)), u1 = std::cos(out.beta_edge(j + 1));
        for (int k = nn - 1; k >= 0; --k) {  // gx increasing: u increasing, beta decreasing
            const double u = 0.5 * (u0 + u1) + 0.5 * (u0 - u1) * gx[static_cast<size_t>(k)];
            out.node_beta.push_back(std::acos(std::clamp(u, -1.0, 1.0)));
        }
    }
    out.node_beta.push_back(kPi);
    const size_t n = out.node_beta.size();
    out.node_value.assign(n, 0.0);
    std::vector<double> errors(n, 0.0);
    std::vector<std::uint64_t> evals(n, 0);
    in_arena(o.threads, [&] {
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& r) {
                for (size_t i = r.begin(); i != r.end(); ++i)
                    out.node_value[i] = exitance_at(w, e, o, out.node_beta[i], errors[i], evals[i]);
            });
    });

    // Bin means: the Gauss-Legendre rule in u over the zone (weights sum to 2).
    out.bin_mean.assign(static_cast<size_t>(nb), 0.0);
    for (int j = 0; j < nb; ++j) {
        double s = 0;
        for (int k = 0; k < nn; ++k) {
            const size_t node = 1 + static_cast<size_t>(j * nn + (nn - 1 - k));
            s += gw[static_cast<size_t>(k)] * out.node_value[node];
        }
        out.bin_mean[static_cast<size_t>(j)] = 0.5 * s;
    }

    // Monotone cubic slopes (Fritsch-Carlson with Brodlie's weights); 0 at the poles, where M is
    // an even function of beta.
    out.node_slope.assign(n, 0.0);
    for (size_t i = 1; i + 1 < n; ++i) {
        const double h0 = out.node_beta[i] - out.node_beta[i - 1];
        const double h1 = out.node_beta[i + 1] - out.node_beta[i];
        const double d0 = (out.node_value[i] - out.node_value[i - 1]) / h0;
        const double d1 = (out.node_value[i + 1] - out.node_value[i]) / h1;
        if (d0 * d1 <= 0) continue;
        const double w1 = 2 * h1 + h0, w2 = h1 + 2 * h0;
        out.node_slope[i] = (w1 + w2) / (w1 / d0 + w2 / d1);
    }

    double vmax = 0;
    for (double v : out.node_value) vmax = std::max(vmax, std::abs(v));
    for (size_t i = 0; i < n; ++i) {
        const double v = std::abs(out.node_value[i]);
        if (v > 0) out.max_rel_error = std::max(out.max_rel_error, errors[i] / v);
        out.integrand_evaluations += evals[i];
    }
    out.fit_error = w.fit_error();
    out.evaluations = w.evaluations();
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

SphereExitance integrate_sphere(const DiffusionProfile& profile, SphereIntegration o) {
    o.eta = profile.medium().eta;
    o.profile_entry_fresnel = profile.includes_entry_fresnel();
    o.rel_tol = std::max(o.rel_tol, profile.rd_accuracy());
    return integrate_sphere([&profile](double r) { return profile.rd(r); }, o);
}

std::array<double, 2> SphereViewFrame::image_point(int x, int y, double fx, double fy) const {
    return {-half_x + (x + fx) * pixel, half_y - (y + fy) * pixel};
}

SphereViewFrame resolve_view(const SphereView& view) {
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("sphere view: " + what);
    };
    if (view.width < 1 || view.height < 1 || view.width > 16384 || view.height > 16384)
        fail("width and height must lie in [1, 16384]");
    if (!(view.frame_scale > 0) || !std::isfinite(view.frame_scale))
        fail("frame_scale must be finite and > 0");
    if (view.supersampling < 1 || view.supersampling > 64)
        fail("supersampling must lie in [1, 64]");
    SphereViewFrame f;
    f.l = unit(view.to_light, "to_light");
    f.v = unit(view.to_camera, "to_camera");
    const std::array<double, 3>& v = f.v;
    std::array<double, 3> up = view.up;
    if (up[0] == 0 && up[1] == 0 && up[2] == 0) {
        up = std::abs(v[1]) > 0.9 ? std::array<double, 3>{0, 0, v[1] > 0 ? -1.0 : 1.0}
                                  : std::array<double, 3>{0, 1, 0};
    } else {
        up = unit(up, "up");
    }
    // Gram-Schmidt, as volpath: refuse an up vector (nearly) parallel to the viewing direction.
    const double uv = dot(up, v);
    std::array<double, 3> ortho{up[0] - v[0] * uv, up[1] - v[1] * uv, up[2] - v[2] * uv};
    const double len = std::sqrt(dot(ortho, ortho));
    if (!(len > 1e-6)) fail("up must not be parallel to to_camera");
    f.up = {ortho[0] / len, ortho[1] / len, ortho[2] / len};
    // right = forward x up with forward = -v.
    const std::array<double, 3> fw{-v[0], -v[1], -v[2]};
    f.right = unit({fw[1] * f.up[2] - fw[2] * f.up[1], fw[2] * f.up[0] - fw[0] * f.up[2],
                    fw[0] * f.up[1] - fw[1] * f.up[0]},
                   "right");
    const double shorter = std::min(view.width, view.height);
    f.pixel = 2.0 * view.frame_scale / shorter;
    f.half_x = 0.5 * view.width * f.pixel;
    f.half_y = 0.5 * view.height * f.pixel;
    f.width = view.width;
    f.height = view.height;
    return f;
}

std::vector<double> sphere_exitance_image(const SphereExitance& table, const SphereView& view) {
    const SphereViewFrame f = resolve_view(view);
    const int n = view.supersampling;
    std::vector<double> img(static_cast<size_t>(f.width) * static_cast<size_t>(f.height), 0.0);
    tbb::parallel_for(
        tbb::blocked_range<int>(0, f.height), [&](const tbb::blocked_range<int>& rows) {
            for (int y = rows.begin(); y != rows.end(); ++y)
                for (int x = 0; x < f.width; ++x) {
                    double sum = 0;
                    for (int j = 0; j < n; ++j)
                        for (int i = 0; i < n; ++i) {
                            const auto p = f.image_point(x, y, (i + 0.5) / n, (j + 0.5) / n);
                            const double rho2 = p[0] * p[0] + p[1] * p[1];
                            if (!(rho2 < 1)) continue;
                            const double z = std::sqrt(1 - rho2);
                            double nl = 0;
                            for (int k = 0; k < 3; ++k)
                                nl += (p[0] * f.right[static_cast<size_t>(k)] +
                                       p[1] * f.up[static_cast<size_t>(k)] +
                                       z * f.v[static_cast<size_t>(k)]) *
                                      f.l[static_cast<size_t>(k)];
                            sum += table.at(std::acos(std::clamp(nl, -1.0, 1.0)));
                        }
                    img[static_cast<size_t>(y) * static_cast<size_t>(f.width) +
                        static_cast<size_t>(x)] = sum / (n * n * kPi);
                }
        });
    return img;
}

}  // namespace ssslab::approx
