#include "volpath/sphere.h"

#include "core/error.h"
#include "core/hash.h"
#include "core/quadrature.h"
#include "core/rng.h"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

namespace ssslab::volpath {

namespace {

// Bump when a change alters the numbers produced for a given seed.
constexpr const char* kEngineVersion = "volpath-sphere-4";

// Largest tally per batch, in doubles (1 GiB).
constexpr std::size_t kMaxTally = std::size_t(1) << 27;

// Everything a path needs, per tally channel (one channel in kPerChannel mode, three in kHero).
struct Setup {
    int nc = 1;
    WalkRegion region;
    double radius = 1;
    double eta_in = 1;   // medium / ambient index (entering)
    double eta_out = 1;  // ambient / medium index (leaving)
    Vec3 l, e1, e2;      // towards the light, and a basis of the disc perpendicular to it
    Vec3 v, right, up;   // camera frame
    double cos_accept = 1;
    double half_x = 0, half_y = 0, inv_pixel = 0;  // in units of R
    double bins_per_rad = 0;
    SphereLayout layout;
    WalkRules rules;
};

// Distance from p (inside the sphere or on it) along the unit vector w to the sphere: the larger
// root of t^2 + 2 b t + c = 0, b = p . w, c = |p|^2 - R^2 (clamped to <= 0, so a point rounded
// just outside counts as on the surface), in the form without cancellation.
double distance_to_sphere(const Vec3& p, const Vec3& w, double radius) {
    const double b = dot(p, w);
    const double c = std::min(dot(p, p) - radius * radius, 0.0);
    const double s = std::sqrt(b * b - c);
    return b <= 0 ? s - b : -c / (b + s);
}

// Weight `wt` leaving the sphere at the point with unit normal n in direction d, for the camera:
// the cone total and the image layers. `specular`: first-surface reflection.
void tally_camera(const Setup& s, const Vec3& n, const Vec3& d, const double* wt, bool specular,
                  double* tally) {
    const double nv = dot(n, s.v);
    if (!(nv > 0)) return;  // not visible
    const bool in_cone = dot(d, s.v) >= s.cos_accept;
    const SphereLayout& L = s.layout;
    const std::size_t stride = L.per_channel();
    if (in_cone) {
        const std::size_t i = specular ? L.cone_specular() : L.cone_subsurface();
        for (int c = 0; c < s.nc; ++c) tally[static_cast<size_t>(c) * stride + i] += wt[c];
    }
    if (!L.image) return;
    // Orthographic projection along v; the frame in units of R, row 0 at the top.
    const double x = (dot(n, s.right) + s.half_x) * s.inv_pixel;
    const double y = (s.half_y - dot(n, s.up)) * s.inv_pixel;
    if (!(x >= 0 && y >= 0 && x < L.width && y < L.height)) return;
    const std::size_t px =
        static_cast<size_t>(y) * static_cast<size_t>(L.width) + static_cast<size_t>(x);
    for (int c = 0; c < s.nc; ++c) {
        double* T = tally + static_cast<size_t>(c) * stride;
        if (!specular) {
            T[L.layer(SphereLayer::kExitance) + px] += wt[c] * nv;
            if (in_cone) T[L.layer(SphereLayer::kSubsurface) + px] += wt[c];
        } else if (in_cone) {
            T[L.layer(SphereLayer::kSpecular) + px] += wt[c];
        }
        if (in_cone) T[L.layer(SphereLayer::kRadiance) + px] += wt[c];
    }
}

// The walk's geometry: the inside of the sphere (volpath/walk.h).
struct SphereGeometry {
    const Setup& s;
    static constexpr bool multi_region = false;
    const WalkRegion& region(int) const { return s.region; }
    template <int NC>
    WalkBoundary next(const WalkState<NC>& st) const {
        WalkBoundary b;
        b.t = distance_to_sphere(st.p, st.w, s.radius);
        return b;
    }
    template <int NC>
    void arrive(WalkState<NC>& st, WalkBoundary& b) const {
        st.p += st.w * b.t;
        // Back onto the sphere, so that rounding cannot accumulate over many reflections.
        b.n = normalize(st.p);
        st.p = b.n * s.radius;
        st.on_surface = true;
    }
};

// What the sphere does with a walk: Fresnel at the boundary; an exit tallied by its angle from
// the subsolar point, and for the camera.
template <int NC>
struct SphereHooks : TallyLostHooks<NC> {
    const Setup& s;
    // SphereLayout::lost(): the weight at risk when a path reaches the long-path roulette, plus
    // (a truncation, practically never) the weight of a flight ended by kMaxBoundaryHits.
    SphereHooks(const Setup& setup, double* t) : s(setup) {
        this->tally = t;
        this->stride = s.layout.per_channel();
        this->index = s.layout.lost();
    }

    BoundaryAction boundary(WalkState<NC>& st, const WalkBoundary& b, RngStream& rng) {
        if (fresnel_reflects(st.w, b.n, s.eta_out, rng)) return BoundaryAction::kReflect;
        // The path leaves the sphere.
        const SphereLayout& L = s.layout;
        const double cb = std::clamp(dot(b.n, s.l), -1.0, 1.0);
        const double x = std::acos(cb) * s.bins_per_rad;
        const std::size_t bin =
            std::min(static_cast<size_t>(x), static_cast<size_t>(L.beta_bins - 1));
        const double* beta = st.weights.beta;
        for (int c = 0; c < NC; ++c) {
            double* T = this->tally + static_cast<size_t>(c) * L.per_channel();
            T[L.beta() + bin] += beta[c];
            T[L.diffuse()] += beta[c];
            if (st.events == 1) {
                T[L.beta_single() + bin] += beta[c];
                T[L.diffuse_single()] += beta[c];
            }
        }
        tally_camera(s, b.n, st.w, beta, false, this->tally);
        return BoundaryAction::kExit;
    }
};

// Trace one photon from the light; add its contributions to `tally` (nc channels of
// layout.per_channel() elements). Returns the number of scattering events. `hero` is the
// sampling channel in hero mode (ignored with NC == 1). Inside, the one walk of
// volpath/walk.h: per channel analog, or hero with weighted absorption.
template <int NC>
std::uint64_t trace(const Setup& s, RngStream& rng, int hero, double* tally) {
    const SphereLayout& L = s.layout;
    const std::size_t stride = L.per_channel();

    // Entry point uniform on the disc of radius R perpendicular to l: u = (r / R)^2 uniform,
    // and the point of the sphere above it has the normal n with n . l = sqrt(1 - u).
    const double u = rng.uniform();
    const double phi = 2.0 * kPi * rng.uniform();
    const double sr = std::sqrt(u), mu = std::sqrt(1.0 - u);
    const Vec3 n0 = normalize(s.e1 * (sr * std::cos(phi)) + s.e2 * (sr * std::sin(phi)) + s.l * mu);
    double cos_t = 0;
    const double F = fresnel_dielectric(mu, s.eta_in, cos_t);
    {
        double wt[NC];
        for (int c = 0; c < NC; ++c) {
            tally[static_cast<size_t>(c) * stride + L.specular()] += F;
            wt[c] = F;
        }
        if (F > 0) tally_camera(s, n0, reflect(-s.l, n0), wt, true, tally);
    }
    if (F >= 1.0) return 0;  // total reflection at grazing entry (eta below the ambient index)

    WalkState<NC> st;
    st.weights.hero = hero;
    st.weights.start(1.0 - F);
    st.p = n0 * s.radius;
    st.w = refract(-s.l, n0, s.eta_in, cos_t);
    st.on_surface = true;
    SphereHooks<NC> hooks(s, tally);
    walk(SphereGeometry{s}, st, s.rules, rng, hooks);
    return static_cast<std::uint64_t>(st.events);
}

std::string fingerprint(const SphereScene& sc, const SphereOptions& o, std::int64_t batch,
                        int run) {
    ContentKey k("sphere-checkpoint");
    k.add("engine", kEngineVersion)
        .add("mode", to_string(o.mode))
        .add("run", run)
        .add("seed", o.seed)
        .add("batch_paths", batch)
        .add("long_path_events", o.long_path_events)
        .add("long_path_survival", o.long_path_survival)
        .add("image", o.image)
        .add("radius_cm", sc.radius_cm)
        .add("to_light", sc.to_light)
        .add("to_camera", sc.to_camera)
        .add("up", sc.up)
        .add("frame.width", sc.width)
        .add("frame.height", sc.height)
        .add("frame.scale", sc.frame_scale)
        .add("acceptance_deg", sc.acceptance_deg)
        .add("beta_bins", sc.beta_bins);
    add_to_key(k, "medium.", sc.medium);
    return k.text();
}

bool finite_vec(const Vec3& a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

// The unit vector along a, or std::invalid_argument naming `what`.
Vec3 unit(const Vec3& a, const char* what) {
    const double len = length(a);
    if (!finite_vec(a) || !(len > 1e-300) || !std::isfinite(len))
        throw std::invalid_argument(std::string("volpath sphere: ") + what +
                                    " must be a finite non-zero vector");
    return a * (1.0 / len);
}

// The scene with its vectors normalised and the camera's up resolved.
SphereScene resolved(const SphereScene& scene) {
    SphereScene s = scene;
    s.to_light = unit(scene.to_light, "to_light");
    s.to_camera = unit(scene.to_camera, "to_camera");
    const Vec3& v = s.to_camera;
    if (scene.up.x == 0 && scene.up.y == 0 && scene.up.z == 0) {
        s.up = std::abs(v.y) > 0.9 ? Vec3{0, 0, v.y > 0 ? -1.0 : 1.0} : Vec3{0, 1, 0};
    } else {
        s.up = unit(scene.up, "up");
    }
    // Gram-Schmidt; refuse an up vector (nearly) parallel to the viewing direction.
    const Vec3 ortho = s.up - v * dot(s.up, v);
    if (!(length(ortho) > 1e-6))
        throw std::invalid_argument("volpath sphere: up must not be parallel to to_camera");
    s.up = normalize(ortho);
    return s;
}

// 2 int_a^b F(mu) mu dmu by adaptive Gauss-Legendre (20 nodes on [-1, 1], `x` and `w`).
double fresnel_moment(double eta, double a, double b, const double* x, const double* w, int n,
                      double whole, int depth) {
    auto panel = [&](double lo, double hi) {
        const double c = 0.5 * (lo + hi), r = 0.5 * (hi - lo);
        double sum = 0;
        for (int i = 0; i < n; ++i) {
            const double mu = c + r * x[i];
            sum += w[i] * 2.0 * mu * fresnel_dielectric(mu, eta);
        }
        return sum * r;
    };
    const double m = 0.5 * (a + b);
    const double left = panel(a, m), right = panel(m, b);
    if (depth >= 50 || std::abs(left + right - whole) <= 1e-16) return left + right;
    return fresnel_moment(eta, a, m, x, w, n, left, depth + 1) +
           fresnel_moment(eta, m, b, x, w, n, right, depth + 1);
}

}  // namespace

const char* sphere_engine_version() {
    return kEngineVersion;
}

const char* to_string(SphereLayer layer) {
    switch (layer) {
        case SphereLayer::kExitance:
            return "exitance";
        case SphereLayer::kSubsurface:
            return "subsurface";
        case SphereLayer::kSpecular:
            return "specular";
        case SphereLayer::kRadiance:
            return "radiance";
    }
    return "?";
}

double sphere_specular_reflectance(double eta) {
    if (!(eta > 0) || !std::isfinite(eta))
        throw std::invalid_argument("sphere_specular_reflectance: eta must be positive");
    if (eta == 1.0) return 0.0;
    constexpr int kN = 20;
    std::vector<double> x, w;
    gauss_legendre(kN, x, w);
    // Below the critical cosine (eta < 1: sin(theta) > eta) the reflection is total and
    // contributes mu_c^2; F has a square-root kink there, so the quadrature starts at it.
    const double mu_c = eta < 1 ? std::sqrt(1 - eta * eta) : 0.0;
    double whole = 0;
    {
        const double c = 0.5 * (mu_c + 1), r = 0.5 * (1 - mu_c);
        for (int i = 0; i < kN; ++i) {
            const double mu = c + r * x[i];
            whole += w[i] * 2.0 * mu * fresnel_dielectric(mu, eta);
        }
        whole *= r;
    }
    return mu_c * mu_c + fresnel_moment(eta, mu_c, 1.0, x.data(), w.data(), kN, whole, 0);
}

SphereCamera sphere_camera(const SphereScene& scene) {
    check_sphere(scene, false);
    const SphereScene s = resolved(scene);
    SphereCamera cam;
    cam.v = s.to_camera;
    cam.up = s.up;
    // right = forward x up with forward = -v.
    cam.right = normalize(cross(-cam.v, cam.up));
    const double shorter = std::min(s.width, s.height);
    cam.pixel_cm = 2.0 * s.frame_scale * s.radius_cm / shorter;
    cam.half_x = 0.5 * s.width * cam.pixel_cm;
    cam.half_y = 0.5 * s.height * cam.pixel_cm;
    const double theta = s.acceptance_deg * kPi / 180.0;
    // 1 - cos(theta) = 2 sin^2(theta / 2), exact for small angles.
    const double sh = std::sin(0.5 * theta);
    cam.solid_angle = 4.0 * kPi * sh * sh;
    return cam;
}

void check_sphere(const SphereScene& scene, bool image, ChromaticMode mode) {
    require_homogeneous(scene.medium, "volpath: the sphere");
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("volpath sphere: " + what);
    };
    if (!(scene.radius_cm > 0) || !std::isfinite(scene.radius_cm))
        fail("radius_cm must be finite and > 0");
    const Medium& m = scene.medium;
    if (!(m.eta > 0) || !(m.eta_above > 0) || !std::isfinite(m.eta) || !std::isfinite(m.eta_above))
        fail("indices of refraction (eta, eta_above) must be finite and > 0");
    for (int c = 0; c < 3; ++c) {
        const double a = m.sigma_a_per_cm[c], sg = m.sigma_s_per_cm[c], g = m.g[c];
        if (!(a >= 0) || !(sg >= 0) || !std::isfinite(a) || !std::isfinite(sg))
            fail(std::string("channel ") + kChannelNames[c] +
                 ": sigma_a and sigma_s must be finite and >= 0");
        if (!(g > -1 && g < 1))
            fail(std::string("channel ") + kChannelNames[c] + ": g must lie in (-1, 1)");
    }
    (void)resolved(scene);  // direction vectors
    if (scene.width < 1 || scene.height < 1 || scene.width > 16384 || scene.height > 16384)
        fail("width and height must lie in [1, 16384]");
    if (!(scene.frame_scale > 0) || !std::isfinite(scene.frame_scale))
        fail("frame_scale must be finite and > 0");
    if (!(scene.acceptance_deg > 0 && scene.acceptance_deg <= 90))
        fail("acceptance_deg must lie in (0, 90]");
    if (scene.beta_bins < 1 || scene.beta_bins > 10'000'000) fail("beta_bins must lie in [1, 1e7]");
    SphereLayout L;
    L.beta_bins = scene.beta_bins;
    L.width = scene.width;
    L.height = scene.height;
    L.image = image;
    const std::size_t size = L.per_channel() * (mode == ChromaticMode::kHero ? 3 : 1);
    if (size > kMaxTally)
        throw InfeasibleError("volpath sphere: a " + std::to_string(scene.width) + " x " +
                              std::to_string(scene.height) + " image needs a tally of " +
                              std::to_string(size) + " doubles per batch (limit 2^27 = 1 GiB, " +
                              "held 2 x threads + 2 times); use a smaller image");
}

double SphereRun::mean(int c, std::size_t i) const {
    if (mode == ChromaticMode::kHero)
        return runs[0].mean[static_cast<size_t>(c) * layout.per_channel() + i];
    return runs[static_cast<size_t>(c)].mean[i];
}

double SphereRun::se(int c, std::size_t i) const {
    if (mode == ChromaticMode::kHero)
        return runs[0].se[static_cast<size_t>(c) * layout.per_channel() + i];
    return runs[static_cast<size_t>(c)].se[i];
}

double SphereRun::beta_edge(int j) const {
    return kPi * j / layout.beta_bins;
}

namespace {

// The run's tallies as results: exitance per zone of beta (over the zone's area), the totals,
// the acceptance cone's intensities, each with its standard error.
void fold_results(SphereRun& out) {
    const SphereScene& sc = out.scene;
    const Medium& m = sc.medium;
    const SphereCamera& cam = out.camera;
    const SphereLayout& L = out.layout;
    const double R = sc.radius_cm;
    out.specular_expected = sphere_specular_reflectance(m.eta / m.eta_above);
    const double to_intensity = kPi * R * R / cam.solid_angle;
    for (int c = 0; c < 3; ++c) {
        out.exitance[c].resize(static_cast<size_t>(L.beta_bins));
        out.exitance_se[c].resize(static_cast<size_t>(L.beta_bins));
        for (int j = 0; j < L.beta_bins; ++j) {
            // Zone area over pi R^2: 2 (cos b0 - cos b1) = 4 sin((b0 + b1) / 2) sin((b1 - b0) / 2).
            const double b0 = out.beta_edge(j), b1 = out.beta_edge(j + 1);
            const double zone = 4.0 * std::sin(0.5 * (b0 + b1)) * std::sin(0.5 * (b1 - b0));
            const size_t i = L.beta() + static_cast<size_t>(j);
            out.exitance[c][static_cast<size_t>(j)] = out.mean(c, i) / zone;
            out.exitance_se[c][static_cast<size_t>(j)] = out.se(c, i) / zone;
            const size_t is = L.beta_single() + static_cast<size_t>(j);
            out.exitance_single[c].push_back(out.mean(c, is) / zone);
            out.exitance_single_se[c].push_back(out.se(c, is) / zone);
        }
        out.diffuse_single[c] = out.mean(c, L.diffuse_single());
        out.diffuse_single_se[c] = out.se(c, L.diffuse_single());
        out.diffuse[c] = out.mean(c, L.diffuse());
        out.diffuse_se[c] = out.se(c, L.diffuse());
        out.specular[c] = out.mean(c, L.specular());
        out.specular_se[c] = out.se(c, L.specular());
        out.lost[c] = out.mean(c, L.lost());
        out.lost_se[c] = out.se(c, L.lost());
        out.intensity_subsurface[c] = out.mean(c, L.cone_subsurface()) * to_intensity;
        out.intensity_subsurface_se[c] = out.se(c, L.cone_subsurface()) * to_intensity;
        out.intensity_specular[c] = out.mean(c, L.cone_specular()) * to_intensity;
        out.intensity_specular_se[c] = out.se(c, L.cone_specular()) * to_intensity;
    }
}

// The run's image layers (SphereLayer), per unit irradiance, with their standard errors and the
// engine's metadata.
LayeredImage sphere_image(const SphereRun& out, const SphereOptions& o) {
    const SphereScene& sc = out.scene;
    const SphereCamera& cam = out.camera;
    const SphereLayout& L = out.layout;
    const double R = sc.radius_cm;
    LayeredImage img(sc.width, sc.height);
    const double a_pix = cam.pixel_cm * cam.pixel_cm;
    // Per photon weight -> layer value: flux pi R^2 E0 per photon; exitance / pi.
    const double to_exitance = R * R / a_pix;
    const double to_radiance = kPi * R * R / (a_pix * cam.solid_angle);
    for (int k = 0; k < kSphereLayers; ++k) {
        const auto layer = static_cast<SphereLayer>(k);
        const double f = layer == SphereLayer::kExitance ? to_exitance : to_radiance;
        ImageLayer& mean = img.add_layer(to_string(layer), 3);
        ImageLayer& err = img.add_layer(std::string(to_string(layer)) + ".stderr", 3);
        const size_t off = L.layer(layer);
        for (int y = 0; y < sc.height; ++y)
            for (int x = 0; x < sc.width; ++x) {
                const size_t px =
                    static_cast<size_t>(y) * static_cast<size_t>(sc.width) + static_cast<size_t>(x);
                for (int c = 0; c < 3; ++c) {
                    mean.at(x, y, c) = static_cast<float>(out.mean(c, off + px) * f);
                    err.at(x, y, c) = static_cast<float>(out.se(c, off + px) * f);
                }
            }
    }
    img.metadata()["ssslab.engine"] = kEngineVersion;
    img.metadata()["ssslab.seed"] = std::to_string(o.seed);
    img.metadata()["ssslab.photons"] = std::to_string(out.runs[0].samples);
    img.metadata()["ssslab.mode"] = to_string(o.mode);
    img.metadata()["ssslab.units"] =
        "per unit irradiance E0 [1/sr]; exitance layer: M / pi; radiance layers: acceptance "
        "cone of half-angle " +
        std::to_string(sc.acceptance_deg) + " deg";
    return img;
}

}  // namespace

SphereRun simulate_sphere(const SphereScene& scene, const SphereOptions& o) {
    check_sphere(scene, o.image, o.mode);
    if (o.long_path_events < 0 || !(o.long_path_survival > 0 && o.long_path_survival <= 1))
        throw std::invalid_argument(
            "volpath sphere: long_path_events must be >= 0 and long_path_survival in (0, 1]");
    SphereRun out;
    out.scene = resolved(scene);
    out.camera = sphere_camera(scene);
    out.mode = o.mode;
    out.layout.beta_bins = scene.beta_bins;
    out.layout.width = scene.width;
    out.layout.height = scene.height;
    out.layout.image = o.image;
    const SphereScene& sc = out.scene;
    const Medium& m = sc.medium;

    SampleBudget budget = o.budget;
    if (!budget.any()) budget.samples = 1'000'000;
    std::int64_t batch = o.batch_paths;
    if (batch <= 0) {
        const bool fixed = budget.samples && !budget.seconds && !budget.rel_error;
        batch = default_batch_samples(budget);
        if (o.image) {
            const auto two_frames = static_cast<std::int64_t>(2 * out.layout.pixels());
            batch = std::max(
                batch, fixed ? std::min(two_frames, (*budget.samples + 31) / 32) : two_frames);
        }
    }
    if (o.mode == ChromaticMode::kHero) batch = (batch + 2) / 3 * 3;  // whole hero cycles

    Setup base;
    base.radius = sc.radius_cm;
    base.eta_in = m.eta / m.eta_above;
    base.eta_out = m.eta_above / m.eta;
    base.l = sc.to_light;
    basis(base.l, base.e1, base.e2);
    const SphereCamera& cam = out.camera;
    base.v = cam.v;
    base.right = cam.right;
    base.up = cam.up;
    base.cos_accept = 1.0 - cam.solid_angle / (2.0 * kPi);
    base.half_x = cam.half_x / sc.radius_cm;
    base.half_y = cam.half_y / sc.radius_cm;
    base.inv_pixel = sc.radius_cm / cam.pixel_cm;
    base.bins_per_rad = sc.beta_bins / kPi;
    base.layout = out.layout;
    base.rules.long_survival = o.long_path_survival;

    const bool hero = o.mode == ChromaticMode::kHero;
    const int nruns = hero ? 1 : 3;
    const std::size_t stride = out.layout.per_channel();
    for (int run = 0; run < nruns; ++run) {
        Setup s = base;
        s.nc = hero ? 3 : 1;
        std::array<double, 3> sigma_t{}, sigma_s{}, g{};
        for (int c = 0; c < s.nc; ++c) {
            const int mc = hero ? c : run;
            const size_t i = static_cast<size_t>(c);
            sigma_t[i] = m.sigma_a_per_cm[mc] + m.sigma_s_per_cm[mc];
            sigma_s[i] = m.sigma_s_per_cm[mc];
            g[i] = m.g[mc];
        }
        s.region = WalkRegion::make(sigma_t, sigma_s, g);
        PencilOptions rule;  // the pencil's rule for long_path_events = 0
        rule.long_path_events = o.long_path_events;
        s.rules.long_events = long_path_threshold(m, rule, hero ? -1 : run);
        // Hero mode weights absorption (the pencil's analog hero is faster on chromatic media;
        // this engine's version pins the weighted one).
        s.rules.absorption = hero ? Absorption::kWeighted : Absorption::kAnalog;
        const int stream = hero ? 3 : run;

        BatchRunOptions bo;
        bo.tally_size = stride * static_cast<size_t>(s.nc);
        bo.batch_samples = batch;
        bo.budget = budget;
        bo.fingerprint = fingerprint(sc, o, batch, stream);
        o.apply_run(bo, stream);
        // Budget quantity: the least precise channel's total diffuse exit.
        bo.quantity = least_precise_channel(
            stride, s.nc,
            [L = out.layout](const BatchAccumulator&, std::size_t) { return L.diffuse(); });

        const std::uint64_t seed = o.seed;
        const std::uint64_t bsz = static_cast<std::uint64_t>(batch);
        auto simulate = [&s, seed, stream, hero, bsz](std::uint64_t index, std::int64_t n,
                                                      double* tally) -> std::uint64_t {
            RngStream rng(seed, rng_domain::kVolpath + 16 + static_cast<std::uint32_t>(stream),
                          index);
            std::uint64_t events = 0;
            for (std::int64_t i = 0; i < n; ++i) {
                if (hero) {
                    const int h =
                        static_cast<int>((index * bsz + static_cast<std::uint64_t>(i)) % 3);
                    events += trace<3>(s, rng, h, tally);
                } else {
                    events += trace<1>(s, rng, 0, tally);
                }
            }
            return events;
        };
        out.runs.push_back(run_batches(bo, simulate));
        const BatchRunResult& r = out.runs.back();
        out.seconds += r.seconds;
        out.paths += r.samples;
        out.events += r.work;
        if (r.reason == BatchStop::kInterrupted) {
            out.interrupted = true;
            return out;
        }
    }

    fold_results(out);
    if (o.image) out.image = sphere_image(out, o);
    return out;
}

}  // namespace ssslab::volpath
